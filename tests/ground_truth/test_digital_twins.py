# SPDX-License-Identifier: AGPL-3.0-or-later
"""The digital twins (docs/digital-twins.md): scenes/twin_raytrix_r12.pov and
scenes/twin_lytro_illum.pov render at reduced size (a crop around the sensor's centre), and their
white images are what the optics, worked out here, says.

Raytrix R12 (setting R12-A): the double-Gauss of lenses/ at f/4, the array 56.86 mm behind its
rear principal plane (paraxial data from the tests' own tracer, plenoptic_testing.lens_tracer),
three microlens types with d < f. A ray from the exit pupil's point P (D' in front of the array)
through the point u of a microlens (from its centre; focal length f) reaches the sensor (d behind)
at the microimage centre plus u (1 + d/D' - d/f) - P d/D': a white microimage is the lens's
hexagonal aperture scaled by b = |1 + d/D' - d/f| convolved with the exit pupil's disc scaled by
d/D'. Second moments add: per axis, b^2 5 R^2 / 24 (a regular hexagon of circumradius R = p/sqrt 3)
plus r^2 / 4 (a disc of radius r = XP d / (2 D')) plus 1/12 (the pixel's box), in pixels^2. Checked
for each lens type, (k - l) mod 3 of the skew indices (specification.md), at f/8 and f/16 (the
microimages of f/4 overlap, the camera warns), within 3 %; the three types differ by more.
(The microimage CSV's (k, l) are the row form; the type rule is on the skew indices.)
The microimage centres are the lattice p (D' + d)/D' / s apart (23.30 px), as the CSV has them.

Lytro Illum: a thin lens of 9.98445 mm at f/2 focused at 2 m, f/2 microlenses of 20 um at d = f,
1.4 um pixels, a GRBG 10-bit read-out: b = d/D is negligible, so each white microimage is the
aperture's disc, A d / D across (14.25 px), and the fraction of a green site's light over the
sensor is pi (A d / 2D)^2 over the hexagonal cell's area (spacing^2 sqrt 3 / 2); the raw is a
GRBG mosaic of 10-bit values above the black level.
"""
import csv
import math
import os
import subprocess
import sys

import numpy as np

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt

SCENES = os.path.join(pt.SOURCE_DIR, "scenes")
LENSES = os.path.join(pt.SOURCE_DIR, "lenses")


def render_scene(args, scene, name, width, height, declare=()):
    work = os.path.join(args.work, "twins")
    os.makedirs(work, exist_ok=True)
    out = os.path.join(work, name + ".png")
    for leftover in os.listdir(work):
        if leftover.startswith(name + "."):
            os.remove(os.path.join(work, leftover))
    cmd = [args.povray, "+I" + os.path.join(SCENES, scene), "+L" + SCENES, "+L" + LENSES, "+O" + out,
           "+W%d" % width, "+H%d" % height, "-D", "-P", "+FN16", "File_Gamma=1.0"] + ["Declare=%s" % d for d in declare]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600, cwd=work)
    assert run.returncode == 0 and os.path.exists(out), (run.stdout + run.stderr)[-3000:]
    return os.path.join(work, name), run.stdout + run.stderr


def double_gauss(f_number):
    rows = lt.parse_lens_file(open(os.path.join(LENSES, "double_gauss_50mm_tronnier_f2.dat")).read())
    full = lt.Lens(rows)
    lens = lt.Lens(rows, stop_diameter=full.stop_diameter * lt.paraxial_data(full).f_number / f_number)
    return lens, lt.paraxial_data(lens)


R12_PITCH, R12_D_ARRAY, R12_PIXEL = 0.12744, 0.33713, 0.0055
R12_F = (0.58267, 0.52402, 0.56057)
R12_W, R12_H = 240, 180


def test_raytrix_r12_twin_white_images_are_the_optics(args):
    stem, log = render_scene(args, "twin_raytrix_r12.pov", "twin_r12", R12_W, R12_H, ["Dataset_Samples=16"])
    meta = pt.load_metadata(stem + ".plenoptic.json")
    lens, par = double_gauss(4.0)
    L = lens.length
    # The array 56.86 mm behind the rear principal plane; D' from the exit pupil.
    D = 56.86 - (L - par.rear_principal_z)
    assert abs(meta["main_lens"]["distance_mm"] - D) < 1e-5, (meta["main_lens"]["distance_mm"], D)
    Dp = D + (L - par.exit_pupil_z)
    d, p, s = R12_D_ARRAY, R12_PITCH, R12_PIXEL
    spacing = p * (Dp + d) / Dp / s
    # The focus this puts the lens at (docs/digital-twins.md): 440.4 mm from the front principal plane.
    s_o = 1 / (1 / par.efl - 1 / 56.86)
    print("R12 twin: EFL %.3f mm, D %.4f mm behind the rear vertex, D' %.3f mm, focus %.1f mm from H (%.1f mm from the "
          "front vertex), microimage spacing %.3f px" % (par.efl, D, Dp, s_o, s_o - par.front_principal_z, spacing))
    assert abs(lt.paraxial_image_distance(lens, s_o - par.front_principal_z) - D) < 1e-6

    # The centres: the lattice p (D' + d) / D' apart, on the axis at the sensor's centre.
    with open(stem + ".microimages.csv") as f:
        rows = [r for r in csv.DictReader(f)]
    k = np.array([float(r["k"]) for r in rows])
    l = np.array([float(r["l"]) for r in rows])
    u = np.array([float(r["u"]) for r in rows])
    v = np.array([float(r["v"]) for r in rows])
    # The CSV's (k, l) are the row form: centres ((k + (l mod 2) / 2) p, l p sqrt 3 / 2) in the
    # array, projected from the exit pupil's centre; the optics frame's x points left in the
    # picture (specification.md, section 2).
    x = (k + np.mod(l, 2) / 2) * p * (Dp + d) / Dp
    y = l * p * math.sqrt(3) / 2 * (Dp + d) / Dp
    eu, ev = pt.sensor_to_pixel(x, y, R12_W, R12_H, s, s)
    worst = max(np.abs(u - eu).max(), np.abs(v - ev).max())
    print("R12 twin: %d microimage centres, largest distance from the lattice worked out here %.4f px" % (len(u), worst))
    assert worst < 0.02, worst

    # The type rule is on the skew indices (k_s, l), centres k_s (p, 0) + l (p/2, p sqrt 3 / 2).
    types = np.mod(k - np.floor(l / 2) - l, 3).astype(int)
    R = p / math.sqrt(3)
    results = {}
    for N in (8.0, 16.0):
        _, parN = double_gauss(N)
        r = parN.exit_pupil_diameter * d / Dp / 2 / s
        white = pt.load(stem + ".white.f%g.png" % N)[..., 0].astype(np.float64)  # grey
        yy, xx = np.mgrid[0:R12_H, 0:R12_W]
        for t in range(3):
            b = abs(1 + d / Dp - d / R12_F[t])
            expected = b * b * 5 * (R / s) ** 2 / 24 + r * r / 4 + 1 / 12
            measured = []
            for i in np.nonzero(types == t)[0]:
                if not (13 <= u[i] <= R12_W - 14 and 13 <= v[i] <= R12_H - 14):
                    continue
                window = (xx - u[i]) ** 2 + (yy - v[i]) ** 2 <= 11 ** 2
                w = white[window]
                du, dv = xx[window] - u[i], yy[window] - v[i]
                measured.append(0.5 * (w * (du * du + dv * dv)).sum() / w.sum())
            m = float(np.median(measured))
            results[(N, t)] = (m, expected)
            print("R12 twin, white image f/%g, lens type %d (f %.5f mm, b %.4f): per-axis variance %.3f px^2 measured "
                  "over %d microimages, %.3f expected" % (N, t, R12_F[t], b, m, len(measured), expected))
            assert len(measured) >= 10
            assert abs(m / expected - 1) < 0.03, (N, t, m, expected)
        # The three types are told apart: their expected variances differ by more than the tolerance.
        e = sorted(results[(N, t)][1] for t in range(3))
        assert min(e[1] / e[0], e[2] / e[1]) > 1.06, e
    # The metadata's microimage diameter is the exit pupil's image through a lens centre.
    assert abs(meta["microimage_lattice"]["microimage_diameter_px"] - par.exit_pupil_diameter * d / Dp / s) < 1e-6


ILLUM_W, ILLUM_H = 420, 300
ILLUM_F, ILLUM_N, ILLUM_FOCUS_MM = 9.98445, 2.0, 2000.0
ILLUM_PITCH, ILLUM_MICRO_F, ILLUM_PIXEL = 0.020, 0.040087, 0.0014


def test_lytro_illum_twin_white_image_and_raw(args):
    stem, log = render_scene(args, "twin_lytro_illum.pov", "twin_illum", ILLUM_W, ILLUM_H, ["Dataset_Samples=16"])
    meta = pt.load_metadata(stem + ".plenoptic.json")
    read_out = meta["sensor"]["read_out"]
    assert (read_out["bayer"], read_out["bit_depth"], read_out["black_level_dn"]) == ("grbg", 10, 64)
    raw = pt.read_pixels(stem + ".raw.png", native=True)
    raw = np.asarray(raw, dtype=np.float64)
    if raw.ndim == 3:
        assert np.all(raw[..., :1] == raw[..., :raw.shape[2]]), "the raw is grey: one value per site"
        raw = raw[..., 0]
    assert raw.shape == (ILLUM_H, ILLUM_W)
    assert raw.max() <= 1023 and raw.min() >= 0
    # GRBG: the scene's red sphere (the picture's middle) is brighter on R sites than on B sites.
    D = ILLUM_F * ILLUM_FOCUS_MM / (ILLUM_FOCUS_MM - ILLUM_F)
    d = ILLUM_MICRO_F
    diameter = ILLUM_F / ILLUM_N * d / D / ILLUM_PIXEL
    spacing = ILLUM_PITCH * (D + d) / D / ILLUM_PIXEL
    assert abs(meta["microimage_lattice"]["microimage_diameter_px"] - diameter) < 1e-6
    assert abs(np.hypot(*meta["microimage_lattice"]["basis_px"][0]) - spacing) < 1e-6

    white = pt.read_pixels(stem + ".white.png", native=True)
    white = np.asarray(white, dtype=np.float64)
    if white.ndim == 3:
        white = white[..., 0]
    green = np.zeros(white.shape, bool)
    green[0::2, 0::2] = True  # GRBG: G at the top left and bottom right of each 2 x 2 cell
    green[1::2, 1::2] = True
    signal = white - 64
    # A site inside a disc sees the whole aperture: its value; the fraction of green sites' light
    # over the picture is the disc's share of the cell.
    yy, xx = np.mgrid[0:ILLUM_H, 0:ILLUM_W]
    full = float(np.median(signal[green & (signal > 0.5 * signal[green].max())]))
    fraction = float(signal[green].mean()) / full
    expected = math.pi * (diameter / 2) ** 2 / (spacing ** 2 * math.sqrt(3) / 2)
    measured_diameter = 2 * math.sqrt(fraction * spacing ** 2 * math.sqrt(3) / 2 / math.pi)
    print("Illum twin: D %.4f mm, microimages %.3f px across, %.3f px apart; white image: lit fraction %.4f (expected "
          "%.4f), diameter %.3f px" % (D, diameter, spacing, fraction, expected, measured_diameter))
    assert abs(measured_diameter / diameter - 1) < 0.02, (measured_diameter, diameter)
    # R and B sites differ in a colourful scene: the mosaic is there (R at even rows' odd columns).
    red, blue = raw[0::2, 1::2], raw[1::2, 0::2]
    assert abs(red.mean() - blue.mean()) > 5, (red.mean(), blue.mean())


def test_twin_data_set_specs_list_their_items(args):
    """The data-set specs of the twins (scenes/twin_*.toml) are valid: plenoptic-dataset lists their
    items (the settings times the seeded poses; the focus sweep), at the sensors' full sizes."""
    import json
    import tomllib
    expected = {"twin_raytrix_r12.toml": (15, (4080, 3068)), "twin_lytro_illum.toml": (4, (7728, 5368))}
    for name, (count, size) in expected.items():
        spec = os.path.join(SCENES, name)
        run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-dataset"), "items", spec],
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stderr[-2000:]
        items = [json.loads(line.split(" ", 1)[1]) for line in run.stdout.splitlines()]
        assert len(items) == count, (name, len(items))
        with open(spec, "rb") as f:
            data = tomllib.load(f)
        assert (data["width"], data["height"]) == size
        assert all(item["Dataset_White_Image"] == 1 for item in items)
    r12 = [json.loads(line.split(" ", 1)[1]) for line in subprocess.run(
        [sys.executable, os.path.join(args.tools, "plenoptic-dataset"), "items", os.path.join(SCENES, "twin_raytrix_r12.toml")],
        capture_output=True, text=True, timeout=120).stdout.splitlines()]
    assert sorted({item["Twin_Setting"] for item in r12}) == [1, 2, 3]
