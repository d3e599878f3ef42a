# SPDX-License-Identifier: AGPL-3.0-or-later
"""The digital twins exported to the community's formats (docs/digital-twins.md, "Exporting the
twins"): each twin rendered at reduced size, exported with plenoptic-export to every format that
accepts it, read back by the export tests' readers (tests/export: written there from each
format's documentation) and checked against optics worked out here.

Raytrix R12, `Twin_Main_Lens 2` (thick_lens: the double-Gauss's paraxial equivalent), R12-A, with
its depth maps. Paraxial data from the tests' own tracer (plenoptic_testing.lens_tracer): the
array 56.86 mm behind the rear principal plane, D' = that plus the rear principal plane's distance
from the exit pupil; microimage spacing p (D' + d) / D' / s.
  - raytrix: the XML's diameter is that spacing; every lit microimage centre of the render's
    microimages.csv has a lattice point of the toolbox's reading of the XML within 0.01 px, one
    to one; each lens's XML type is our (k_s - l) mod 3; each type's depth range is where
    libpleno's blur radius (p/2)(d/f + 1/v - 1) is at most one pixel; the disparity image at the
    picture's centre is diameter / v of the board's centre (on the axis, 0.30 m from the front
    vertex), v = (b - D) / d from the thick lens's b (object distance from the front principal
    plane);
  - kiel: every lens once, at its microimages.csv centre, with d, f d / (f - d) and f / p;
  - refused, by name: eslf and views (a focused camera of three lens types), compote (a thick
    lens; libpleno's lens is thin), and the traced lens (variant 1) by raytrix and kiel.
Raytrix R12, `Twin_Main_Lens 3` (a thin lens of the same paraxial numbers, at the front principal
plane), through plenoptic-targets (twin_raytrix_r12_camera.inc is the camera file): the
numbers the camera file writes are the tracer's (EFL, the principal plane, R12-B's focus); compote:
F, N, D, d and the micro-image pitch p (D + d) / D / s; every centre on a lit microimages.csv centre
(0.01 px); every BAP radius libpleno's (p/2)(d/f + 1/v - 1)/s from the corner's thin-lens image.
Lytro Illum, with its depth map: eslf: tiles equal the decoder's light field after the format's
quantisation, the lenslet size the metadata's usable disc, LFToolbox's hexagonal grid model on
every metadata centre; views: the geometry is the thin lens's (baseline s D / d, focal length
D / p view pixels, plane in focus 2 m) and the centre view's disparity at its centre is
baseline x focal x (1/Z - 1/2 m) for the sphere's point on the axis (Z from the scene's numbers);
refused: raytrix (one lens type), kiel (d = f), compote (not a target set).
"""
import csv
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import plenoptic_testing as pt

# The twins test's renderer and the export tests' readers (pytest imports test files by path).
HERE = os.path.dirname(os.path.abspath(__file__))
for folder in (HERE, os.path.join(HERE, "..", "export")):
    if folder not in sys.path:
        sys.path.insert(0, folder)
from test_digital_twins import LENSES, SCENES, double_gauss, render_scene  # noqa: E402
from test_compote import mesh_node, read_js, read_rows  # noqa: E402
from test_export_eslf import expected_angular_count, lfbuild_hex_grid, read_eslf  # noqa: E402
from test_export_views import read_pfm  # noqa: E402
from test_raytrix_kiel import read_calib_xml, read_csv_centres, toolbox_lattice, toolbox_types  # noqa: E402

PITCH, D_MLA, S = 0.12744, 0.33713, 0.0055
FOCAL = (0.58267, 0.52402, 0.56057)
W, H = 240, 180
BOARD_MM = 300.0  # R12-A's board centre, from the front vertex, on the axis


def export(args, image, fmt, out, *extra):
    return subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-export"), image, "--to", fmt, out, "-q",
                           *extra], capture_output=True, text=True, timeout=300)


def our_type(k, l):
    """(k_s - l) mod 3 of a lens in the row form (k, l) of microimages.csv."""
    return ((k - math.floor(l / 2)) - l) % 3


def r12_optics():
    """D (rear principal plane -> array), D' (exit pupil -> array), the lens and its paraxial data."""
    lens, par = double_gauss(4.0)
    big_d = 56.86
    return big_d, big_d + (par.rear_principal_z - par.exit_pupil_z), lens, par


@pytest.fixture(scope="module")
def r12_thick(args):
    stem, _ = render_scene(args, "twin_raytrix_r12.pov", "twin_r12_thick", W, H,
                           ["Dataset_Samples=4", "Dataset_White_Image=0", "Dataset_Depth_Map=1", "Twin_Main_Lens=2"])
    out = {}
    for fmt in ("raytrix", "kiel"):
        folder = os.path.join(args.work, "twins", "r12_thick_" + fmt)
        run = export(args, stem + ".png", fmt, folder)
        assert run.returncode == 0, (fmt, run.stderr)
        out[fmt] = folder
    return stem, out


def test_r12_thick_lens_is_the_prescriptions_paraxial_equivalent(r12_thick):
    stem, _ = r12_thick
    meta = pt.load_metadata(stem + ".plenoptic.json")
    big_d, big_dp, lens, par = r12_optics()
    main = meta["main_lens"]
    assert main["type"] == "thick_lens" and abs(main["focal_length_mm"] - par.efl) < 1e-6, main["focal_length_mm"]
    assert abs(main["distance_mm"] - (big_d - (lens.length - par.rear_principal_z))) < 1e-5
    spacing = PITCH * (big_dp + D_MLA) / big_dp / S
    assert abs(np.hypot(*meta["microimage_lattice"]["basis_px"][0]) - spacing) < 1e-6
    assert os.path.exists(stem + ".microimages.csv") and os.path.exists(stem + ".virtual_depth.exr")


def test_r12_raytrix_xml_places_every_centre(r12_thick):
    stem, out = r12_thick
    big_d, big_dp, lens, par = r12_optics()
    cal = read_calib_xml(os.path.join(out["raytrix"], "twin_r12_thick.xml"))
    spacing = PITCH * (big_dp + D_MLA) / big_dp / S
    assert abs(cal["diameter"] - spacing) < 1e-6, (cal["diameter"], spacing)
    centres = read_csv_centres(stem + ".microimages.csv")
    lattice = toolbox_lattice(cal, W, H, reach=12)
    keys = list(lattice)
    points = np.array([lattice[k] for k in keys])
    colour_to_type = toolbox_types(cal)
    matched, worst = set(), 0.0
    for (k, l), (u, v) in centres.items():
        if not (-0.5 <= u < W - 0.5 and -0.5 <= v < H - 0.5):
            continue
        j = int(np.argmin(np.hypot(points[:, 0] - u, points[:, 1] - v)))
        worst = max(worst, float(np.hypot(points[j, 0] - u, points[j, 1] - v)))
        assert keys[j] not in matched, "two centres on one lattice point"
        matched.add(keys[j])
        alpha, beta = keys[j]
        assert colour_to_type[((-alpha) % 3 + beta) % 3] == our_type(k, l), (k, l)
    print("R12 thick_lens: %d microimage centres, largest distance from the XML's lattice %.2g px (spacing %.4f px)"
          % (len(matched), worst, spacing))
    assert len(matched) >= 60 and worst < 0.01, (len(matched), worst)
    # Depth ranges: libpleno's blur radius of one pixel at each end (1/v = 1 - d/f -+ 2 s / p).
    for t, f in enumerate(FOCAL):
        c, e = 1 - D_MLA / f, 2 * S / PITCH
        low, high = cal["types"][t]["range"]
        assert abs(low - 1 / (c + e)) < 1e-9 and abs(high - (1 / (c - e) if c - e > 0 else 100.0)) < 1e-9, (t, low, high)
    # The disparity at the picture's centre: the board's centre, on the axis.
    z = BOARD_MM + par.front_principal_z  # from the front principal plane (z of the tracer: from the front vertex)
    b = par.efl * z / (z - par.efl)
    v = (b - big_d) / D_MLA
    disparity = read_pfm(os.path.join(out["raytrix"], "twin_r12_thick_disp.pfm"))
    centre = float(np.median(disparity[H // 2 - 1:H // 2 + 1, W // 2 - 1:W // 2 + 1]))
    print("R12 thick_lens: virtual depth of the board's centre %.4f, disparity %.4f px, the export's %.4f px"
          % (v, spacing / v, centre))
    assert abs(centre / (spacing / v) - 1) < 0.01, (centre, spacing / v)


def test_r12_kiel_lenses_at_their_centres(r12_thick):
    stem, out = r12_thick
    with open(os.path.join(out["kiel"], "twin_r12_thick.json")) as f:
        entries = json.load(f)
    centres = read_csv_centres(stem + ".microimages.csv")
    cal = read_calib_xml(os.path.join(out["raytrix"], "twin_r12_thick.xml"))
    seen = set()
    for e in entries:
        k, l = e["row_form_index"]
        assert (k, l) not in seen
        seen.add((k, l))
        u, v = centres[(k, l)]
        assert e["pixel_coord"] == [v, u], (k, l)
        f = FOCAL[our_type(k, l)]
        assert e["focal_type"] == our_type(k, l) and e["focal_length"] == D_MLA
        assert abs(e["focus_distance"] - f * D_MLA / (f - D_MLA)) < 1e-12 and abs(e["fstop"] - f / PITCH) < 1e-12
        assert abs(e["diameter"] - cal["diameter"]) < 1e-12
        assert os.path.exists(os.path.join(out["kiel"], e["relative_color_filename"]))
    inside = {key for key, (u, v) in centres.items() if -0.5 <= u < W - 0.5 and -0.5 <= v < H - 0.5}
    assert len(seen) >= 60 and inside <= seen, (len(seen), len(inside - seen))


def test_r12_refusals(args, r12_thick):
    stem, _ = r12_thick
    for fmt, words in (("eslf", "focused (2.0) camera"), ("views", "3 lens types")):
        run = export(args, stem + ".png", fmt, os.path.join(args.work, "twins", "r12_refused_" + fmt))
        assert run.returncode == 2 and words in run.stderr, (fmt, run.stderr)
    traced, _ = render_scene(args, "twin_raytrix_r12.pov", "twin_r12_traced", 60, 45,
                             ["Dataset_Samples=1", "Dataset_White_Image=0"])
    for fmt in ("raytrix", "kiel"):
        run = export(args, traced + ".png", fmt, os.path.join(args.work, "twins", "r12_traced_" + fmt))
        assert run.returncode == 2 and "traced prescription" in run.stderr, (fmt, run.stderr)


def camera_file(args, name, variant):
    path = os.path.join(args.work, "twins", name + ".inc")
    return pt.write_text(path, "#declare Twin_Main_Lens = %d;\n#declare Dataset_White_Image = 0;\n"
                               "#declare Dataset_Samples = 4;\n#include \"twin_raytrix_r12_camera.inc\"\n" % variant)


def target_set(args, name, variant, count, width, height):
    out = os.path.join(args.work, "twins", name)
    run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-targets"), camera_file(args, name, variant),
                          "+L" + LENSES, "--out", out, "--count", str(count), "--seed", "3", "--distance", "0.29", "0.31",
                          "--tilt", "15", "--target", "checkerboard:5x9:0.002", "--width", str(width), "--height",
                          str(height), "--povray", args.povray, "--project", args.project],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return out


def test_r12_thin_lens_numbers_are_the_tracers():
    """The numbers twin_raytrix_r12_camera.inc writes for Twin_Main_Lens 3 are the prescription's
    paraxial data (the tracer's, to the digits written)."""
    _, _, lens, par = r12_optics()
    with open(os.path.join(SCENES, "twin_raytrix_r12_camera.inc")) as f:
        text = f.read()
    assert "focal_length %.6f" % par.efl in text and "distance %.6f" % par.efl in text
    assert "location <0, 0, -%.9f>" % (par.front_principal_z / 1000) in text
    assert "focus_distance %.9f" % (1.0 + par.front_principal_z / 1000) in text
    # R12-A: the traced lens's rear vertex -> array distance is 56.86 mm behind the rear principal plane.
    assert "distance %.6f" % (56.86 - (lens.length - par.rear_principal_z)) in text


def test_r12_thin_lens_compote(args):
    folder = target_set(args, "r12_thin_targets", 3, 2, W, H)
    out = os.path.join(args.work, "twins", "r12_thin_compote")
    run = export(args, os.path.join(folder, "target_000.png"), "compote", out, "-O", "project=" + args.project)
    assert run.returncode == 0, run.stderr
    _, _, lens, par = r12_optics()
    F, N, big_d = 50.358167, 4.0, 56.86
    camera = read_js(os.path.join(out, "config", "camera.js"))
    intr = read_js(os.path.join(out, "config", "intrinsics.js"))
    assert camera["main_lens"] == {"aperture": N, "f": F} and camera["I"] == 3 and camera["mode"] == 2
    assert intr["D"] == big_d and intr["d"] == D_MLA and abs(F - par.efl) < 1e-6
    mia = intr["mia"]["mesh"]
    spacing = PITCH * (big_d + D_MLA) / big_d / S
    assert abs(mia["pitch"][0][0] - spacing) < 1e-9
    measured = np.array([(float(r["u"]), float(r["v"])) for r in read_rows(os.path.join(folder, "target_000.microimages.csv"))
                         if r["u"]])
    centres = read_rows(os.path.join(out, "obs", "center.csv"))
    assert len(centres) >= 60
    for r in centres:
        u, v = float(r["u"]), float(r["v"])
        assert np.hypot(*(mesh_node(mia, int(r["k"]), int(r["l"])) - (u, v))) < 0.01
        assert np.min(np.hypot(*(measured - (u, v)).T)) < 0.01
    # BAP: every corner image's radius from its thin-lens image, the lens at the front principal
    # plane (the camera's location, 23.2357 mm behind the front vertex).
    bap = read_rows(os.path.join(out, "obs", "bap.csv"))
    views = read_js(os.path.join(folder, "targets.json"))["views"]
    checked = 0
    for view in views:
        images = {}
        with open(os.path.join(folder, view["points"])) as f:
            for row in csv.DictReader(f):
                images[(round(float(row["u"]), 6), round(float(row["v"]), 6))] = (int(row["lens_k"]), int(row["lens_l"]),
                                                                                   float(row["z"]))
        for r in (r for r in bap if int(r["frame"]) == view["view"]):
            k, l, z_world = images[(round(float(r["u"]), 6), round(float(r["v"]), 6))]
            z = (z_world + par.front_principal_z / 1000) * 1000.0
            b = F * z / (z - F)
            vd = (b - big_d) / D_MLA
            expected = PITCH / 2 * (D_MLA / FOCAL[our_type(k, l)] + 1 / vd - 1) / S
            assert abs(float(r["rho"]) - expected) < 1e-4, (r, expected)
            checked += 1
    print("R12 thin lens: %d micro-image centres, %d BAP radii checked" % (len(centres), checked))
    assert checked >= 50


def test_r12_thick_lens_is_refused_by_compote(args):
    folder = target_set(args, "r12_thick_targets", 2, 1, 120, 90)
    run = export(args, os.path.join(folder, "target_000.png"), "compote", os.path.join(args.work, "twins", "r12_thick_c"),
                 "-O", "project=" + args.project)
    assert run.returncode == 2 and "thin lens" in run.stderr and "thick_lens" in run.stderr, run.stderr


IW, IH = 420, 300


@pytest.fixture(scope="module")
def illum(args):
    stem, _ = render_scene(args, "twin_lytro_illum.pov", "twin_illum_export", IW, IH,
                           ["Dataset_Samples=4", "Dataset_White_Image=0", "Dataset_Depth_Map=1"])
    out = {}
    for fmt in ("eslf", "views"):
        folder = os.path.join(args.work, "twins", "illum_" + fmt)
        run = export(args, stem + ".png", fmt, folder)
        assert run.returncode == 0, (fmt, run.stderr)
        out[fmt] = folder
    return stem, out


def test_illum_eslf_tiles_are_the_decoders_views(illum):
    import plenoptic_lf as plf
    stem, out = illum
    eslf = os.path.join(out["eslf"], "twin_illum_export.eslf.png")
    lf_file, doc = read_eslf(eslf)
    raw = plf.read_raw(stem + ".png")
    meta = plf.load_metadata(stem + ".plenoptic.json", (raw.shape[1], raw.shape[0]))
    lf = plf.decode(raw, meta)
    T, S_, n_v, n_u, _ = lf.data.shape
    assert lf_file.shape == (n_v, n_u, T, S_, 4)
    expected = np.floor(np.clip(lf.data.astype(np.float64), 0, 1) * 65535 + 0.5).astype(np.uint16)
    got = lf_file[..., :3].transpose(2, 3, 0, 1, 4)
    assert int(np.count_nonzero(got != expected)) == 0
    with open(stem + ".plenoptic.json") as f:
        meta_doc = json.load(f)
    n = expected_angular_count(meta_doc)
    assert doc["DecodeOptions"]["LFSize"][:2] == [n, n], (doc["DecodeOptions"]["LFSize"], n)
    model = doc["LensletGridModel"]
    grid = lfbuild_hex_grid(model).reshape(-1, 2) - 1.0
    grid = grid[(grid[:, 0] >= 0) & (grid[:, 0] <= IW - 1) & (grid[:, 1] >= 0) & (grid[:, 1] <= IH - 1)]
    lattice = meta_doc["microimage_lattice"]
    origin, basis = np.array(lattice["origin_px"], float), np.array(lattice["basis_px"], float).T
    kl = np.linalg.solve(basis, (grid - origin).T).T
    assert len(grid) > 400 and np.abs((np.rint(kl) - kl) @ basis.T).max() < 1e-6
    print("Illum: ESLF of %d x %d lenses, tiles of %d x %d, equal to the decoder's" % (S_, T, n, n))


def test_illum_views_disparity_is_the_thin_lens_answer(illum):
    stem, out = illum
    with open(os.path.join(out["views"], "views.json")) as f:
        doc = json.load(f)
    F, focus, micro_f, pixel, pitch = 9.98445, 2000.0, 0.040087, 0.0014, 0.020
    big_d = F * focus / (focus - F)
    baseline, focal_px = pixel * big_d / micro_f, big_d / pitch
    g = doc["geometry"]
    assert abs(g["baseline_mm"] - baseline) < 1e-9 and abs(g["focal_length_px"] - focal_px) < 1e-6
    assert abs(g["focus_distance_mm"] - focus) < 1e-6
    # The axis meets the scene's sphere (plenoptic_scene.inc: camera at <0, 0.45, -2> looking at
    # <0, 0.3, 0>, sphere at <0.02, 0.25, 0> of radius 0.25) at Z along the axis.
    c, look = np.array([0, 0.45, -2.0]), np.array([0, 0.3, 0.0])
    axis = (look - c) / np.linalg.norm(look - c)
    oc = c - np.array([0.02, 0.25, 0.0])
    p = float(axis @ oc)
    z = (-p - math.sqrt(p * p - (float(oc @ oc) - 0.25 ** 2))) * 1000.0
    expected = baseline * focal_px * (1 / z - 1 / focus)
    centre = doc["reference_view"]
    disparity = read_pfm(os.path.join(out["views"], "disparity_%02d_%02d.pfm" % (centre["row"], centre["column"])))
    h, w = disparity.shape
    got = float(np.median(disparity[(h - 1) // 2:h // 2 + 1, (w - 1) // 2:w // 2 + 1]))
    print("Illum: the sphere on the axis at %.1f mm: disparity %.5f px, the centre view's %.5f px" % (z, expected, got))
    assert abs(got / expected - 1) < 0.03, (got, expected)


def test_illum_refusals(args, illum):
    stem, _ = illum
    for fmt, words in (("raytrix", "lens type 0"), ("kiel", "<= d"), ("compote", "targets.json")):
        run = export(args, stem + ".png", fmt, os.path.join(args.work, "twins", "illum_refused_" + fmt))
        assert run.returncode == 2 and words in run.stderr, (fmt, run.stderr)
