# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode on renders through real main lenses (docs/real-lenses.md, docs/ground-truth.md).

The lens: the 22 mm f/3.5 wide-angle of lenses/ (Laikin's retrofocus), at f/3.5.
Every expected value comes from the reference tracer of the tests (plenoptic_testing.lens_tracer:
paraxial data, exact trace) and POV-Ray's stock perspective camera, never from the decoder:

  - traced prescription focused at 1.2 m on a chart, rectangular array, Bayer read-out (16 bits,
    noise-free in effect) and its white image (in DN): plenoptic-decode RAW --white WHITE
    decodes; its centre view equals the
    stock render from the entrance pupil's centre, each view pixel read where the lens centre's
    real chief ray (traced through the prescription) meets the chart at the focus;
  - the decoder samples each microimage around its measured centre from <image>.microimages.csv
    (a synthetic raw whose values are the pixel coordinates gives back the centre it sampled at),
    lenses that get no light stay black and are marked; without the file it refuses and names
    microimage_centres; --hci and --total-focus refuse the prescription with the reason; the
    refocus labels (slope_to_distance) are the tracer's paraxial images;
  - thick_lens (the paraxial equivalent) focused at 0.4 m, hexagonal array, planes at 0.15 and
    3 m: the centre view equals the stock render from the entrance pupil (the object-side chief ray through the
    pupil's centre and the lens centre's conjugate, closed form); the disparity between the
    outermost views equals the paraxial prediction (chief rays through the exit pupil, the
    thin-lens equation between the principal planes), and slope_to_distance maps it back to the
    planes' distances; --hci writes depths from the entrance pupil and the closed-form disparity,
    and its outermost views lie that disparity apart;
  - thick_lens, focused (2.0) camera: --total-focus is the stock render from the entrance pupil's
    centre (angles from the exit pupil's centre times the pupils' magnification);
  - the metadata reader accepts thick_lens and prescription, and refuses a broken paraxial block
    naming the field.
"""

import configparser
import copy
import json
import math
import os
import shutil
import subprocess

import numpy as np
from scipy import ndimage

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt

LENS_NAME = "wide_angle_22mm_laikin_f3.5.dat"
LENS_PATH = os.path.join(pt.SOURCE_DIR, "lenses", LENS_NAME)
F_NUMBER = 3.5
FOCUS_MM = 1200.0
W, H = 240, 180
PIXEL = 0.06
PITCH = 0.6  # 10-pixel microimages
# The thick lens: 20-pixel microimages and planes near and far from a close focus, so that the
# wide-angle's views show parallax.
THICK_W, THICK_H, THICK_PIXEL, THICK_FOCUS_MM = 480, 360, 0.03, 400.0
LOSSLESS = "bayer grbg bit_depth 16 full_well 1e14 exposure 1e14"

CHART = """#declare Lit = finish { emission 1 diffuse 0 ambient 0 }
background { rgb 0 }
box { <-2, -2, %(z)r>, <0, 0, %(z2)r> pigment { checker rgb <0.8, 0.25, 0.2> rgb <0.35, 0.1, 0.1> scale 0.09 } finish { Lit } }
box { <0, -2, %(z)r>, <2, 0, %(z2)r> pigment { checker rgb <0.25, 0.7, 0.3> rgb <0.1, 0.3, 0.1> scale 0.09 } finish { Lit } }
box { <-2, 0, %(z)r>, <0, 2, %(z2)r> pigment { checker rgb <0.2, 0.3, 0.8> rgb <0.05, 0.1, 0.35> scale 0.09 } finish { Lit } }
box { <0, 0, %(z)r>, <2, 2, %(z2)r> pigment { checker rgb <0.85, 0.8, 0.3> rgb <0.35, 0.3, 0.1> scale 0.09 } finish { Lit } }
cylinder { <0.12, 0.08, %(zc)r>, <0.12, 0.08, %(z)r>, 0.1 pigment { rgb 0.95 } finish { Lit } }
""" % {"z": FOCUS_MM / 1000, "z2": FOCUS_MM / 1000 + 0.01, "zc": FOCUS_MM / 1000 - 1e-4}

Z_NEAR, Z_FAR = 0.15, 3.0  # metres from the front vertex
PLANES = """#declare Tex = texture {
  pigment { bozo color_map { [0 rgb <0.05, 0.1, 0.4>] [0.5 rgb <0.9, 0.9, 0.6>] [1 rgb <0.6, 0.1, 0.05>] } }
  finish { emission 1 diffuse 0 ambient 0 } }
background { rgb 0 }
box   { <-2, 0, %r>, <2, 2, %r> texture { Tex scale 0.012 } }
plane { z, %r texture { Tex scale 0.3 } }
""" % (Z_NEAR, Z_NEAR + 1e-4, Z_FAR)


class Optics:
    """The camera's first-order optics from the reference tracer, in the optics frame (mm, z
    from the rear vertex towards the scene; specification.md and real-lenses.md, "Frame")."""

    def __init__(self, f_number=F_NUMBER, focus_mm=FOCUS_MM, pixel=PIXEL):
        rows = lt.parse_lens_file(open(LENS_PATH).read())
        full = lt.Lens(rows)
        # f-number = EFL / entrance pupil, and the entrance pupil scales with the stop.
        self.lens = lt.Lens(rows, stop_diameter=full.stop_diameter * lt.paraxial_data(full).f_number / f_number)
        self.focus_mm, self.pixel = focus_mm, pixel
        p = lt.paraxial_data(self.lens)
        assert abs(p.f_number - f_number) < 1e-9
        self.L = L = self.lens.length
        self.F = p.efl
        self.D = lt.paraxial_image_distance(self.lens, focus_mm)  # rear vertex -> array
        self.z_xp, self.z_ep = L - p.exit_pupil_z, L - p.entrance_pupil_z
        self.z_h, self.z_h2 = L - p.front_principal_z, L - p.rear_principal_z
        self.xp, self.ep = p.exit_pupil_diameter, p.entrance_pupil_diameter
        self.Dp = self.z_xp + self.D  # exit pupil -> array
        self.d = PITCH * self.Dp / self.xp  # f-number matched microlenses (d / p = working f-number)
        self.s_i = self.z_h2 + self.D
        self.s_o = self.s_i * self.F / (self.s_i - self.F)
        # The thin-lens equation between the principal planes puts the array's conjugate at the focus.
        assert abs(self.z_h + self.s_o - (L + focus_mm)) < 1e-6 * focus_mm

    def lens_centre(self, sensor_xy):
        """The lens centre (x, y on the array) whose microimage centre is this sensor point: the
        lattice projects lens centres from the exit pupil's centre."""
        return np.asarray(sensor_xy) * self.Dp / (self.Dp + self.d)

    def image_distance_behind_xp(self, z_mm):
        """Exit pupil -> the paraxial image of the plane z_mm in front of the front vertex."""
        return self.z_xp + lt.paraxial_image_distance(self.lens, z_mm)

    def slope(self, z_mm):
        """Refocus shift of a plane, microimage-centre pixels per pixel of angular offset: a pixel du
        off its microimage centre sees through the exit pupil's plane at du s D'/d; the line from
        there through the plane's image (b behind the pupil) meets the array (D' behind it) moved
        by (D'/b - 1) du s D'/d, i.e. (D'/b - 1)(D' + d)/d microimage-centre pixels."""
        b = self.image_distance_behind_xp(z_mm)
        return (self.Dp / b - 1) * (self.Dp + self.d) / self.d


def camera(optics, main_lens, grid, sensor="", extra=""):
    return ("camera { plenoptic location <0, 0, 0> look_at <0, 0, 1>\n"
            "  main_lens { %s f_number %r focus_distance %r }\n"
            "  microlens_array { %s pitch %r focal_length %r distance %r }\n"
            "  sensor { pixel_size %r %s }\n"
            "  samples 16 %s }\n"
            % (main_lens, F_NUMBER, optics.focus_mm / 1000, grid, PITCH, optics.d, optics.d, optics.pixel, sensor, extra))


def render(args, name, scene, width=W, height=H):
    png = pt.render(args.povray, args.work, name, pt.SCENE_HEADER + scene, width, height, timeout=600)
    return png, os.path.splitext(png)[0]


def run_decode(args, *options):
    return subprocess.run(pt.decoder(args.tools) + list(options), capture_output=True, text=True, timeout=600)


def stock_view(args, name, optics, scene, angle_deg, width=480, height=360):
    """POV-Ray's perspective camera at the entrance pupil's centre, looking along the axis."""
    z = (optics.z_ep - optics.L) / 1000.0
    cam = ("camera { perspective location <0, 0, %r> look_at <0, 0, 1> right x*%d/%d up y angle %.12g }\n"
           % (z, width, height, angle_deg))
    png = pt.render(args.povray, args.work, name, pt.SCENE_HEADER + scene + cam, width, height)
    return pt.read_linear(png)[..., :3]


def stock_pixels(X, Y, Z, angle_deg, width=480, height=360):
    """Continuous pixel coordinates (centre of pixel (i, j) at (i, j)) of directions (X, Y, Z) from
    the stock camera: right x*W/H spans the angle, up y the height in proportion."""
    t = math.tan(math.radians(angle_deg) / 2)
    xn = X / Z / t
    yn = Y / Z / (t * height / width)
    return (xn + 1) / 2 * width - 0.5, (1 - yn) / 2 * height - 0.5


def sample(image, u, v, blur_px):
    """The image box-blurred over blur_px pixels (one view pixel's patch), read bilinearly at (u, v)."""
    size = max(1, int(round(blur_px)))
    out = []
    for c in range(image.shape[2]):
        blurred = ndimage.uniform_filter(image[..., c], size=size)
        out.append(ndimage.map_coordinates(blurred, [v, u], order=1, mode="nearest"))
    return np.stack(out, axis=-1)


def ncc(a, b):
    a = a - a.mean()
    b = b - b.mean()
    return float((a * b).sum() / math.sqrt((a * a).sum() * (b * b).sum()))


def centre_view_positions(out, meta):
    """The decoded light field's centre view and, per view pixel, the raw pixel it was read around
    (the lattice position lightfield.json states)."""
    description = json.load(open(os.path.join(out, "lightfield.json")))
    data = np.load(os.path.join(out, "lightfield.npy"))
    T, S, n_v, n_u, _ = data.shape
    view = data[:, :, n_v // 2, n_u // 2, :].astype(np.float64)
    A = np.array(description["grid_s_vector_px"])
    R = np.array(description["grid_t_vector_px"])
    s0, t0 = description["grid_origin_index"]
    origin = np.array(meta["microimage_lattice"]["origin_px"])
    tt, ss = np.mgrid[0:T, 0:S].astype(np.float64)
    u = origin[0] + (s0 + ss) * A[0] + (t0 + tt) * R[0]
    v = origin[1] + (s0 + ss) * A[1] + (t0 + tt) * R[1]
    return view, u, v, description, data


def sensor_xy(u, v, width=W, height=H, pixel=PIXEL):
    """Optics-frame sensor point (mm) of continuous pixel coordinates (specification.md, section 2)."""
    return pt.sensor_point(u, v, width, height, pixel, pixel)


def lifted_apertures(lens):
    """The same lens with every clear aperture opened as wide as its sphere allows: chief rays
    ignore the apertures (real-lenses.md, "Chief rays")."""
    rows = [s._replace(aperture=200.0) if s.is_stop else s._replace(aperture=min(200.0, 1.999 * abs(s.radius)))
            for s in lens.surfaces]
    return lt.Lens(rows, stop_diameter=200.0)


def traced_chart_points(optics, c):
    """Where the real chief ray of lens centres c (N, 2; on the array) meets the chart: traced
    from the lens centre towards the exit pupil's centre through the prescription, mm, optics x, y."""
    lens = lifted_apertures(optics.lens)
    origins = np.column_stack([c, np.full(len(c), optics.L + optics.D)])  # lens frame: z = L - z_optics
    target = np.array([0.0, 0.0, optics.L - optics.z_xp])
    result = lt.trace_image_to_object(lens, origins, target - origins)
    assert result.passed.all(), "every chief ray passes the lens with its apertures lifted"
    p, d = result.points, result.directions
    t = (-optics.focus_mm - p[:, 2]) / d[:, 2]
    return p[:, 0] + t * d[:, 0], p[:, 1] + t * d[:, 1]


# ============================================================================================
# The traced prescription: Bayer raw, white image, measured microimage centres

_PRESCRIPTION = {}


def prescription_render(args):
    if "png" not in _PRESCRIPTION:
        optics = Optics()
        scene = CHART + camera(optics, 'lens_file "%s"' % LENS_NAME, "rectangular", LOSSLESS, "white_image")
        png, stem = render(args, "real_lens_prescription", scene)
        _PRESCRIPTION.update(png=png, stem=stem, optics=optics)
    return _PRESCRIPTION["png"], _PRESCRIPTION["stem"], _PRESCRIPTION["optics"]


def test_prescription_bayer_raw_with_white_image_decodes_to_the_stock_view(args):
    png, stem, optics = prescription_render(args)
    meta = pt.load_metadata(stem + ".plenoptic.json")
    assert meta["main_lens"]["type"] == "prescription"
    assert meta["sensor"]["read_out"]["bayer"] == "grbg"
    assert os.path.exists(stem + ".microimages.csv") and os.path.exists(stem + ".white.png")
    out = os.path.join(args.work, "real_lens_prescription.lightfield")
    run = run_decode(args, stem + ".raw.png", "--white", stem + ".white.png", "-o", out, "--no-gif")
    assert run.returncode == 0, "plenoptic-decode decodes the real-lens raw (stderr: %s)" % run.stderr[-2000:]
    assert "demosaiced" in run.stderr and "devignetted" in run.stderr, run.stderr

    view, u, v, description, _ = centre_view_positions(out, meta)
    T, S = view.shape[:2]
    assert S >= 18 and T >= 12, "decoded %d x %d lenses" % (S, T)
    # Per view pixel: the lens centre, its real chief ray's point on the chart, and that point
    # seen from the entrance pupil's centre.
    c = optics.lens_centre(np.column_stack([a.ravel() for a in sensor_xy(u, v)]))
    hx, hy = traced_chart_points(optics, c)
    depth = FOCUS_MM + (optics.L - optics.z_ep)  # entrance pupil -> chart
    # The paraxial answer (no distortion): the lens centre's conjugate on the chart.
    px, py = -c[:, 0] * optics.s_o / optics.s_i, -c[:, 1] * optics.s_o / optics.s_i
    reach = max(np.abs(hx).max(), np.abs(hy).max() * W / H, np.abs(px).max(), np.abs(py).max() * W / H)
    angle = 2 * math.degrees(math.atan(1.1 * reach / depth))
    stock = stock_view(args, "real_lens_prescription_stock", optics, CHART, angle)
    cell_px = PITCH * optics.s_o / optics.s_i / depth / math.tan(math.radians(angle) / 2) * 240
    traced = sample(stock, *stock_pixels(hx, hy, depth, angle), cell_px).reshape(T, S, 3)
    paraxial = sample(stock, *stock_pixels(px, py, depth, angle), cell_px).reshape(T, S, 3)
    lit = ~np.array(description["dark_mask"], bool)
    inner = np.zeros((T, S), bool)
    inner[1:-1, 1:-1] = True
    keep = lit & inner
    score, score_paraxial = ncc(view[keep], traced[keep]), ncc(view[keep], paraxial[keep])
    error = np.abs(view - traced)[keep]
    distortion = np.hypot(hx - px, hy - py).max() / (PITCH * optics.s_o / optics.s_i)
    print("prescription: centre view %d x %d; against the stock view along the traced chief rays NCC %.4f, "
          "median |difference| %.4f; along paraxial rays NCC %.4f (distortion moves chart points by up to %.2f "
          "view pixels)" % (S, T, score, np.median(error), score_paraxial, distortion))
    pt.save_png(os.path.join(args.work, "real_lens_prescription_views.png"),
                np.clip(np.kron(np.concatenate([view, traced], axis=1), np.ones((6, 6, 1))), 0, 1))
    assert score > 0.9, "the centre view looks like the stock view from the entrance pupil (NCC %.4f)" % score
    # Devignetted with the white image, the values are the chart's radiance.
    assert np.median(error) < 0.05, np.median(error)


def test_prescription_samples_around_the_measured_centres(args):
    """A raw whose channels are u, v and 1 (bilinear interpolation is exact on it) decodes to the
    position each microimage was sampled around: the CSV's centre of that lens."""
    import plenoptic_lf as plf
    png, stem, optics = prescription_render(args)
    meta = plf.load_metadata(stem + ".plenoptic.json", (W, H))
    vv, uu = np.mgrid[0:H, 0:W].astype(np.float32)
    ramp = np.stack([uu, vv, np.ones_like(uu)], axis=-1)
    lf = plf.decode(ramp, meta)
    T, S, n_v, n_u, _ = lf.shape
    centre = lf.data[:, :, n_v // 2, n_u // 2, :].astype(np.float64)
    csv = np.genfromtxt(stem + ".microimages.csv", delimiter=",", names=True)
    lattice = json.load(open(stem + ".plenoptic.json"))["microimage_lattice"]
    o, a, b = np.array(lattice["origin_px"]), np.array(lattice["basis_px"][0]), np.array(lattice["basis_px"][1])
    positions = o + np.outer(csv["k"], a) + np.outer(csv["l"], b)  # rectangular: row form = skew
    grid = lf.grid_position(np.arange(S)[None, :].repeat(T, 0), np.arange(T)[:, None].repeat(S, 1))
    nearest = np.argmin(((grid[..., None, :] - positions[None, None]) ** 2).sum(-1), axis=-1)
    expected_u, expected_v = csv["u"][nearest], csv["v"][nearest]
    lit = np.isfinite(expected_u)
    shift = np.hypot(expected_u - grid[..., 0], expected_v - grid[..., 1])[lit]
    got = np.hypot(centre[..., 0] - expected_u, centre[..., 1] - expected_v)[lit]
    print("measured centres: %d lit lenses decoded, %d dark; the centres lie up to %.3f px off the lattice "
          "(mean %.3f); sampled within %.2g px of them" % (lit.sum(), (~lit).sum(), shift.max(), shift.mean(), got.max()))
    assert shift.max() > 0.1, "behind this lens some centres leave the lattice (the test can tell them apart)"
    assert got.max() < 1e-3, "every lit lens is sampled around its measured centre (worst %.3g px)" % got.max()
    assert (lf.dark == ~lit).all(), "exactly the lenses without a centre are marked dark"
    assert (lf.data[~lit] == 0).all(), "dark lenses stay black"

    # Lenses the file lists without a centre (no light; this render's field has none, so three are
    # emptied in a copy) are left black and marked; the others keep their centres.
    folder = os.path.join(args.work, "real_lens_dark")
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    shutil.copy(stem + ".plenoptic.json", os.path.join(folder, "real_lens_prescription.plenoptic.json"))
    lines = open(stem + ".microimages.csv").read().splitlines()
    chosen = [int(nearest[T // 2, S // 2]), int(nearest[1, 1]), int(nearest[T - 2, S - 3])]
    for index in chosen:
        cells = lines[1 + index].split(",")
        lines[1 + index] = ",".join(cells[:2] + ["", ""] + cells[4:5] + ["", ""])
    with open(os.path.join(folder, "real_lens_prescription.microimages.csv"), "w") as f:
        f.write("\n".join(lines) + "\n")
    lf = plf.decode(ramp, plf.load_metadata(os.path.join(folder, "real_lens_prescription.plenoptic.json"), (W, H)))
    emptied = np.isin(nearest, chosen)
    assert emptied.sum() == 3 and (lf.dark == emptied).all(), "the three emptied lenses, and only they, are dark"
    assert (lf.data[emptied] == 0).all() and (lf.data[~emptied][..., 2] > 0).any()
    kept = lf.data[:, :, n_v // 2, n_u // 2, :].astype(np.float64)
    assert np.hypot(kept[..., 0] - expected_u, kept[..., 1] - expected_v)[~emptied].max() < 1e-3


def test_prescription_refusals_name_the_reason(args):
    png, stem, _ = prescription_render(args)
    for option, words in (("--hci", ("traced prescription", "distortion", "thick_lens")),
                          ("--total-focus", ("traced prescription", "distortion", "thick_lens"))):
        target = os.path.join(args.work, "real_lens_refused" + (".png" if option == "--total-focus" else ""))
        run = run_decode(args, png, option, target)
        lines = [line for line in run.stderr.strip().splitlines() if "error" in line]
        assert run.returncode == 2 and len(lines) == 1, (option, run.returncode, run.stderr)
        assert all(w in lines[0] for w in words), "%s's refusal names why: %s" % (option, lines[0])
        assert not os.path.exists(target)
    # Without the measured centres the decoder cannot place the microimages: it says so and how.
    folder = os.path.join(args.work, "real_lens_no_csv")
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    for suffix in (".png", ".plenoptic.json"):
        shutil.copy(stem + suffix, os.path.join(folder, "scene" + suffix))
    meta = json.load(open(stem + ".plenoptic.json"))
    meta["microimages"]["file"] = "scene.microimages.csv"
    with open(os.path.join(folder, "scene.plenoptic.json"), "w") as f:
        json.dump(meta, f)
    run = run_decode(args, os.path.join(folder, "scene.png"), "-o", os.path.join(folder, "out"))
    assert run.returncode == 2 and "microimage_centres" in run.stderr and "scene.microimages.csv" in run.stderr, run.stderr
    assert not os.path.exists(os.path.join(folder, "out"))
    meta["microimages"] = None
    with open(os.path.join(folder, "scene.plenoptic.json"), "w") as f:
        json.dump(meta, f)
    run = run_decode(args, os.path.join(folder, "scene.png"), "-o", os.path.join(folder, "out"))
    assert run.returncode == 2 and "microimage_centres" in run.stderr and "wrote none" in run.stderr, run.stderr


def test_renamed_prescription_render_finds_its_microimages(args):
    """Data sets rename renders: shot001.raw.png, shot001.plenoptic.json, shot001.microimages.csv
    while the metadata still names the renderer's files. The decoder looks for the metadata's
    microimages.file, then <metadata stem>.microimages.csv, takes --microimages CSV, and refuses a
    centres file that is not this render's (its lens count, or lenses off this picture)."""
    png, stem, _ = prescription_render(args)
    folder = os.path.join(args.work, "real_lens_renamed")
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    out = os.path.join(folder, "out")

    def decoded(raw, *options):
        run = run_decode(args, raw, "-q", "--no-gif", "-o", out, *options)
        lf = np.load(os.path.join(out, "lightfield.npy")) if run.returncode == 0 else None
        shutil.rmtree(out, ignore_errors=True)
        return run, lf

    run, original = decoded(stem + ".raw.png")
    assert run.returncode == 0, run.stderr
    shot = os.path.join(folder, "shot001")
    for suffix in (".raw.png", ".plenoptic.json", ".microimages.csv"):
        shutil.copy(stem + suffix, shot + suffix)
    run, lf = decoded(shot + ".raw.png")
    assert run.returncode == 0, "the renamed render decodes with shot001.microimages.csv: %s" % run.stderr
    assert np.array_equal(lf, original)
    # Elsewhere: the refusal lists what was tried and names the option, which then finds it.
    centres = os.path.join(folder, "centres.csv")
    os.rename(shot + ".microimages.csv", centres)
    run, _ = decoded(shot + ".raw.png")
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    for words in ("real_lens_prescription.microimages.csv", "shot001.microimages.csv", "--microimages CSV"):
        assert words in lines[0], (words, lines[0])
    assert not os.path.exists(out)
    run, lf = decoded(shot + ".raw.png", "--microimages", centres)
    assert run.returncode == 0, run.stderr
    assert np.array_equal(lf, original)
    # Centres that cannot be this render's: one lens fewer; every lens one column over (the
    # same count, lenses off the picture); a missing file.
    rows = open(centres).read().splitlines()
    cut = os.path.join(folder, "cut.csv")
    with open(cut, "w") as f:
        f.write("\n".join(rows[:-1]) + "\n")
    moved = os.path.join(folder, "moved.csv")
    with open(moved, "w") as f:
        f.write("\n".join([rows[0]] + [",".join([str(int(r.split(",")[0]) + 1)] + r.split(",")[1:]) for r in rows[1:]])
                + "\n")
    for csv, words in ((cut, ("lists %d lenses" % (len(rows) - 2), "counts %d" % (len(rows) - 1), "microimages.lenses")),
                       (moved, ("lies outside this %d x %d picture" % (W, H), "another render")),
                       (os.path.join(folder, "nowhere.csv"), ("--microimages", "no such file"))):
        run, _ = decoded(shot + ".raw.png", "--microimages", csv)
        lines = run.stderr.strip().splitlines()
        assert run.returncode == 2 and len(lines) == 1 and all(w in lines[0] for w in words), (csv, run.stderr)
        assert not os.path.exists(out)
    # A lattice that is exact takes no measured centres: the option is refused with the reason.
    thick = json.load(open(shot + ".plenoptic.json"))
    thick["main_lens"]["type"] = "thick_lens"
    with open(os.path.join(folder, "thick.plenoptic.json"), "w") as f:
        json.dump(thick, f)
    run = run_decode(args, shot + ".raw.png", os.path.join(folder, "thick.plenoptic.json"), "-q", "-o", out,
                     "--microimages", centres)
    assert run.returncode == 2 and "thick_lens" in run.stderr and "microimage_lattice" in run.stderr, run.stderr


def test_contact_sheet_says_which_lens_and_marks_the_centres_it_used(args):
    """The title names the microlenses and the main lens apart (not 'hexagonal thin_lens plenoptic
    render' for a traced prescription); the raw crop marks the centres the decoder sampled around:
    the CSV's measured centres behind a prescription, the lattice where it is exact."""
    import plenoptic_lf as plf
    from plenoptic_lf.contact_sheet import crop_marks, sheet_title
    png, stem, optics = prescription_render(args)
    meta = plf.load_metadata(stem + ".plenoptic.json", (W, H))
    title = sheet_title("r.raw.png", meta)
    print(title)
    assert title == ("r.raw.png: rectangular array of thin-lens microlenses behind a traced prescription (%s), %d x %d px"
                     % (LENS_NAME, W, H)), title
    variants = {"thick_lens": "behind a thick lens, the paraxial equivalent of %s" % LENS_NAME,
                "thin_lens": "behind a thin main lens (f = %g mm, f/%g)" % (meta.focal_length_mm, F_NUMBER),
                "pinhole": "behind a pinhole main lens"}
    for lens_type, words in variants.items():
        raw = json.load(open(stem + ".plenoptic.json"))
        raw["main_lens"]["type"] = lens_type
        title = sheet_title("r.raw.png", plf.metadata.Metadata(raw, stem + ".plenoptic.json"))
        assert words in title and "thin-lens microlenses" in title, (lens_type, title)
    # The marks: the CSV's centres of the lit lenses in the crop (within 1e-9 px), which here lie
    # up to about a pixel off the lattice at the edge of the field (the crop: all but a 5 px border).
    csv = np.genfromtxt(stem + ".microimages.csv", delimiter=",", names=True)
    x0, y0, cw, ch = 5, 5, W - 10, H - 10
    u, v, what = crop_marks(meta, x0, y0, cw, ch)
    assert "measured" in what and os.path.basename(stem) + ".microimages.csv" in what, what
    lit = np.isfinite(csv["u"])
    inside = lit & (csv["u"] >= x0 - 0.5) & (csv["u"] <= x0 + cw - 0.5) & (csv["v"] >= y0 - 0.5) & (csv["v"] <= y0 + ch - 0.5)
    expected = np.column_stack([csv["u"][inside], csv["v"][inside]])
    got = np.column_stack([u, v])
    assert len(got) == len(expected) >= 300, (len(got), len(expected))
    worst = max(np.hypot(*(expected - p).T).min() for p in got)
    lattice = json.load(open(stem + ".plenoptic.json"))["microimage_lattice"]
    o, a, b = (np.array(lattice["origin_px"]), np.array(lattice["basis_px"][0]), np.array(lattice["basis_px"][1]))
    off = np.hypot(*(expected - (o + np.outer(csv["k"][inside], a) + np.outer(csv["l"][inside], b))).T).max()
    print("contact sheet: %d centres marked in the crop, within %.2g px of the CSV's (which lie up to %.2f px off the "
          "lattice)" % (len(got), worst, off))
    assert worst < 1e-9 and off > 0.1, (worst, off)
    # Where the lattice is exact (the same metadata as a thick lens), the lattice is marked.
    raw = json.load(open(stem + ".plenoptic.json"))
    raw["main_lens"]["type"] = "thick_lens"
    thick = plf.metadata.Metadata(raw, stem + ".plenoptic.json")
    u, v, what = crop_marks(thick, x0, y0, cw, ch)
    assert "lattice" in what and "measured" not in what, what
    k, l, lu, lv = thick.all_centres()
    keep = (lu >= x0 - 0.5) & (lu <= x0 + cw - 0.5) & (lv >= y0 - 0.5) & (lv <= y0 + ch - 0.5)
    assert np.allclose(np.sort(u), np.sort(lu[keep])) and np.allclose(np.sort(v), np.sort(lv[keep]))


def test_metadata_reader_accepts_real_lenses_and_checks_their_fields(args):
    import plenoptic_lf as plf
    from plenoptic_lf.errors import MetadataError
    png, stem, optics = prescription_render(args)
    raw = json.load(open(stem + ".plenoptic.json"))
    meta = plf.metadata.Metadata(raw, stem + ".plenoptic.json")  # refused before: type "prescription"
    assert abs(meta.exit_pupil_z - optics.z_xp) < 1e-9 and abs(meta.pupil_distance_mm - optics.Dp) < 1e-9
    for lens_type in ("thick_lens", "prescription"):
        for path, value, words in (("paraxial.exit_pupil_diameter_mm", None, "exit_pupil_diameter_mm"),
                                   ("paraxial.rear_principal_plane_z_mm", "x", "rear_principal_plane_z_mm"),
                                   ("paraxial.effective_focal_length_mm", 30.0, "focal_length_mm"),
                                   ("f_number", -4, "f_number"), ("aperture_mm", 0, "aperture_mm"),
                                   ("paraxial", None, "paraxial")):
            broken = copy.deepcopy(raw)
            broken["main_lens"]["type"] = lens_type
            node = broken["main_lens"]
            parts = path.split(".")
            for part in parts[:-1]:
                node = node[part]
            node[parts[-1]] = value
            try:
                plf.metadata.Metadata(broken)
            except MetadataError as e:
                assert words in str(e), (path, str(e))
            else:
                raise AssertionError("%s = %r is refused for %s" % (path, value, lens_type))


def test_slope_labels_follow_the_paraxial_lens(args):
    """slope_to_distance and its inverse against the reference tracer's paraxial images."""
    import plenoptic_lf as plf
    png, stem, optics = prescription_render(args)
    meta = plf.load_metadata(stem + ".plenoptic.json", (W, H))
    for z in (500.0, 700.0, FOCUS_MM, 2500.0, 10000.0):
        kappa = optics.slope(z)
        label = meta.slope_to_distance(kappa) * meta.mm_per_unit
        assert abs(label - z) < 1e-6 * z, "kappa %.6f labelled %.6f mm, the plane is at %g mm" % (kappa, label, z)
        assert abs(meta.distance_to_kappa(z / meta.mm_per_unit) - kappa) < 1e-9 * max(1, abs(kappa))
    # The thin-lens shortcut (distances from one lens plane, D from the rear vertex) is far off here.
    thin = optics.F * optics.D / (optics.D - optics.F)
    assert abs(thin - FOCUS_MM) > 100, thin


# ============================================================================================
# thick_lens: an exact lattice; views, disparity, --hci

_THICK = {}


def thick_render(args):
    if "png" not in _THICK:
        optics = Optics(focus_mm=THICK_FOCUS_MM, pixel=THICK_PIXEL)
        scene = PLANES + camera(optics, 'lens_file "%s" thick_lens' % LENS_NAME, "hexagonal", "", "depth_map")
        png, stem = render(args, "real_lens_thick", scene, THICK_W, THICK_H)
        _THICK.update(png=png, stem=stem, optics=optics)
    return _THICK["png"], _THICK["stem"], _THICK["optics"]


def match_shift(left, right, lo=-6.0, hi=6.0, step=0.01):
    best, best_cost = None, np.inf
    for ds in np.arange(lo, hi + step / 2, step):
        moved = pt.shift_rows(left, ds)
        diff = (right - moved)[:, ~np.isnan(moved[0])]
        if diff.shape[1] < 0.4 * right.shape[1]:
            continue
        cost = np.mean(diff * diff)
        if cost < best_cost:
            best, best_cost = ds, cost
    return best


def test_thick_lens_views_and_refocus_labels(args):
    import plenoptic_lf as plf
    png, stem, optics = thick_render(args)
    width, height = THICK_W, THICK_H
    meta_json = pt.load_metadata(stem + ".plenoptic.json")
    assert meta_json["main_lens"]["type"] == "thick_lens"
    meta = plf.load_metadata(stem + ".plenoptic.json", (width, height))
    lf = plf.decode(plf.read_raw(png, "linear"), meta)
    T, S, n_v, n_u, _ = lf.shape
    cv, cu = lf.centre_index()
    view = lf.view(cv, cu).astype(np.float64)
    grid = lf.grid_position(np.arange(S)[None, :].repeat(T, 0), np.arange(T)[:, None].repeat(S, 1))
    sx, sy = sensor_xy(grid[..., 0], grid[..., 1], width, height, THICK_PIXEL)
    c = optics.lens_centre(np.column_stack([sx.ravel(), sy.ravel()]))
    # The object-side chief ray: from the entrance pupil's centre through the lens centre's
    # conjugate on the plane in focus (thin-lens equation between the principal planes).
    X, Y = -c[:, 0] * optics.s_o / optics.s_i, -c[:, 1] * optics.s_o / optics.s_i
    Z = np.full(len(X), optics.focus_mm + optics.L - optics.z_ep)
    angle = 2 * math.degrees(math.atan(1.1 * max(np.abs(X).max(), np.abs(Y).max() * 4 / 3) / Z[0]))
    stock = stock_view(args, "real_lens_thick_stock", optics, PLANES, angle)
    cell_px = PITCH * optics.s_o / optics.s_i / Z[0] / math.tan(math.radians(angle) / 2) * 240
    reference = sample(stock, *stock_pixels(X, Y, Z, angle), cell_px).reshape(T, S, 3)
    inner = np.zeros((T, S), bool)
    inner[1:-1, 1:-1] = True
    score = ncc(view[inner], reference[inner])
    print("thick lens: centre view %d x %d against the stock view from the entrance pupil: NCC %.4f" % (S, T, score))
    assert score > 0.85, score

    # Disparity between the outermost views of each plane against the paraxial prediction.
    near_rows = grid[:, 0, 1] < height / 2 - 3 * np.hypot(*lf.R)
    far_rows = grid[:, 0, 1] > height / 2 + 3 * np.hypot(*lf.R)
    usable = [iu for iu in range(n_u) if lf.mask[cv, iu]]
    left, right = usable[0], usable[-1]
    baseline = (lf.du[right] - lf.du[left]) / lf.step
    for name, rows, z in (("near", near_rows, Z_NEAR * 1000), ("far", far_rows, Z_FAR * 1000)):
        expected = lf.slope_from_kappa(optics.slope(z))
        views = [plf.gray(lf.view(cv, iu))[rows] for iu in (left, right)]
        ds = match_shift(views[0], views[1])
        measured = ds / baseline
        tolerance = 0.03 * abs(expected) + 0.1 / baseline
        label = lf.slope_to_distance(measured) * 1000
        print("thick lens, %s plane at %g mm: slope %.4f measured, %.4f predicted; labelled %.0f mm"
              % (name, z, measured, expected, label))
        assert abs(measured - expected) <= tolerance, (name, measured, expected, tolerance)
        assert abs(lf.slope_to_distance(expected) * 1000 - z) < 1e-6 * z
        assert abs(1 / label - 1 / z) < 0.2 * abs(1 / z - 1 / optics.focus_mm), (name, label, z)


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"Pf"
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        values = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return values.reshape(height, width)[::-1].astype(np.float64)


def test_thick_lens_hci_export(args):
    png, stem, optics = thick_render(args)
    out = os.path.join(args.work, "real_lens_thick_hci")
    shutil.rmtree(out, ignore_errors=True)
    run = run_decode(args, png, "-q", "--hci", out)
    assert run.returncode == 0, run.stderr[-2000:]
    cfg = configparser.ConfigParser()
    cfg.read(os.path.join(out, "parameters.cfg"))
    n = int(cfg.get("extrinsics", "num_cams_x"))
    depth = read_pfm(os.path.join(out, "gt_depth_lowres.pfm"))
    disparity = read_pfm(os.path.join(out, "gt_disp_lowres.pfm"))
    # Depth from the entrance pupil's plane; the views are pinhole cameras on that plane, the
    # exit pupil's points du pixel D'/d apart imaged by the pupils' magnification.
    pupil_to_vertex = optics.L - optics.z_ep  # entrance pupil -> front vertex, mm
    magnification = optics.xp / optics.ep
    baseline = THICK_PIXEL * optics.Dp / optics.d / magnification
    z0 = optics.focus_mm + pupil_to_vertex
    focal_px = z0 * optics.s_i / optics.s_o / PITCH
    for z in (Z_NEAR, Z_FAR):
        Z = z * 1000 + pupil_to_vertex
        on = np.isclose(depth, Z / 1000, rtol=1e-5)
        assert on.sum() > 0.15 * depth.size, "the plane at %g m lies %.6f m from the entrance pupil: %d px" % (
            z, Z / 1000, on.sum())
        expected = baseline * focal_px * (1 / Z - 1 / z0)
        worst = np.abs(disparity[on] - expected).max()
        print("thick lens --hci: plane at %g m, depth %.6f m, disparity %.5f (expected %.5f)" % (
            z, Z / 1000, np.median(disparity[on]), expected))
        assert worst < 1e-4 * max(1, abs(expected)), (z, worst, expected)
    # The centre camera at the entrance pupil's centre (POV-Ray's z is Blender's y).
    assert abs(float(cfg.get("extrinsics", "center_cam_y_m")) - (optics.z_ep - optics.L) / 1000) < 1e-12
    # The views agree with that disparity: the outermost views of the grid's centre row are
    # (n - 1) disparities apart on each plane (a point at x in view column c is at x - disp (j - c)).
    from PIL import Image

    def grey(index):
        rgb = np.asarray(Image.open(os.path.join(out, "input_Cam%03d.png" % index)), dtype=np.float64) / 255.0
        return rgb.mean(axis=2)

    c = n // 2
    left, right = grey(c * n), grey(c * n + n - 1)
    for z in (Z_NEAR, Z_FAR):
        Z = z * 1000 + pupil_to_vertex
        rows = np.isclose(depth, Z / 1000, rtol=1e-5).all(axis=1)
        rows &= ndimage.binary_erosion(rows, iterations=2)
        expected = baseline * focal_px * (1 / Z - 1 / z0) * (n - 1)
        # right(x) = left(x + (n - 1) disp): the shift that carries the left view onto the right one.
        shift = match_shift(left[rows], right[rows], lo=-3, hi=3)
        print("thick lens --hci: plane at %g m, views 0 and %d of the centre row %.3f px apart, ground truth %.3f"
              % (z, n - 1, -shift, expected))
        assert abs(-shift - expected) < 0.1 + 0.05 * abs(expected), (z, shift, expected)


# ============================================================================================
# thick_lens, focused (2.0) camera: --total-focus

TF_W, TF_H, TF_PIXEL, TF_FOCUS_MM, TF_STEP = 360, 270, 0.01, 150.0, 2.5
TF_PITCH, TF_MICRO_F, TF_ARRAY_D = 0.15, 0.5, 0.75
TF_NEAR, TF_FAR = 0.35, 1.5  # metres from the front vertex: images 2 to 4 d in front of the array
TF_PLANES = """#declare Glow = finish { emission 1 diffuse 0 ambient 0 }
box { <-3, 0, %r>, <3, 3, %r> pigment { checker rgb <0.9, 0.8, 0.3> rgb <0.1, 0.2, 0.6> scale 0.006 } finish { Glow } }
plane { z, %r pigment { checker rgb <0.8, 0.3, 0.2> rgb <0.2, 0.7, 0.3> scale 0.025 } finish { Glow } }
""" % (TF_NEAR, TF_NEAR + 1e-4, TF_FAR)


def test_thick_lens_total_focus_is_a_pinhole_at_the_entrance_pupil(args):
    """The total focus of a focused camera behind the thick lens is the picture of a pinhole at the
    entrance pupil's centre: object-side angles are the image side's (from the exit pupil's centre,
    D' + d to the sensor) times the pupils' magnification."""
    optics = Optics(focus_mm=TF_FOCUS_MM, pixel=TF_PIXEL)
    scene = TF_PLANES + (
        "camera { plenoptic location <0, 0, 0> look_at <0, 0, 1>\n"
        "  main_lens { lens_file \"%s\" thick_lens f_number %r focus_distance %r }\n"
        "  microlens_array { hexagonal pitch %r focal_length %r distance %r }\n"
        "  sensor { pixel_size %r } samples 16 depth_map }\n"
        % (LENS_NAME, F_NUMBER, TF_FOCUS_MM / 1000, TF_PITCH, TF_MICRO_F, TF_ARRAY_D, TF_PIXEL))
    png, stem = render(args, "real_lens_thick_focused", scene, TF_W, TF_H)
    Dp = optics.Dp  # exit pupil -> array
    magnification = optics.xp / optics.ep
    half = math.degrees(math.atan(magnification * TF_W * TF_PIXEL / (2 * (Dp + TF_ARRAY_D))))
    z = (optics.z_ep - optics.L) / 1000.0
    cam = ("camera { perspective location <0, 0, %r> look_at <0, 0, 1> right x*%d/%d up y angle %.12g }\n"
           % (z, TF_W, TF_H, 2 * half))
    stock_png = pt.render(args.povray, args.work, "real_lens_thick_focused_stock", pt.SCENE_HEADER + TF_PLANES + cam,
                          TF_W, TF_H)
    stock = pt.read_linear(stock_png)[..., :3]
    out = os.path.join(args.work, "real_lens_thick_total.exr")
    results = {}
    for name, options in (("map", ()), ("flipped", ("--virtual-depth", "2.5"))):
        run = run_decode(args, png, "-q", "--total-focus", out, "--total-focus-step", str(TF_STEP), *options)
        assert run.returncode == 0, run.stderr[-2000:]
        image = pt.load(out)[..., :3]
        columns = int(math.floor((TF_W - 1) / TF_STEP)) + 1
        rows = int(math.floor((TF_H - 1) / TF_STEP)) + 1
        assert image.shape[:2] == (rows, columns)
        xs, ys = np.meshgrid(np.arange(columns) * TF_STEP + 0.5 * ((TF_W - 1) - (columns - 1) * TF_STEP),
                             np.arange(rows) * TF_STEP + 0.5 * ((TF_H - 1) - (rows - 1) * TF_STEP))
        reference = np.stack([ndimage.map_coordinates(stock[..., c], [ys, xs], order=1) for c in range(3)], axis=-1)
        near = (ys < TF_H / 2 - 12) & (ys > 12) & (xs > 12) & (xs < TF_W - 13)
        far = (ys > TF_H / 2 + 12) & (ys < TF_H - 13) & (xs > 12) & (xs < TF_W - 13)
        # Over R, G and B together: the far plane's two colours have almost the same grey.
        results[name] = {plane: ncc(image[mask], reference[mask]) for plane, mask in (("near", near), ("far", far))}
    print("thick lens total focus against the stock view from the entrance pupil: NCC %s" % results)
    assert results["map"]["near"] > 0.85 and results["map"]["far"] > 0.6, results
    assert results["flipped"]["near"] < 0.5 * results["map"]["near"], results
