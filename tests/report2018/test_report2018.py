# SPDX-License-Identifier: AGPL-3.0-or-later
"""The scenes of scenes/report2018 (docs/report2018.md): every one renders, and the claims the page
makes about them hold, each against an answer computed here from the optics:

- thin-lens camera, sensor 50 mm behind the lens: for f = 0.05, 0.5, 5, 50 and 100 mm the
  picture is POV-Ray's stock pinhole picture blurred by the disc b = A |D (1/F - 1/z) - 1| (so it
  never vanishes, f >= d included), and a disc 0.6 or 1.5 times as wide fits clearly worse;
- bare array tilted 20 degrees: the pixels where the array would lie behind the sensor, beyond
  d / tan 20 from the axis, and only those, are black;
- full camera: over whole cells near the axis the irradiance is the flux through one lens spread
  over its microimage cell, pi a^2 / (D^2 + a^2) / (1 + d/D)^2 for a white scene, at every d
  (overlap included);
- the array translated by 0.4 unit (12 whole pitches) gives the untranslated raw;
- the doubled sensor's centre is the d = 1/8 raw binned 2 x 2.
"""
import glob
import math
import os
import sys

import numpy as np
import pytest
from scipy import signal

import plenoptic_testing as pt

SCENES = os.path.join(pt.SOURCE_DIR, "scenes", "report2018")
NAMES = sorted(os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(SCENES, "*.pov")))

# The report's units (report2018.inc states them; written out again here, in mm).
UNIT = 24.0
SENSOR = 1 * UNIT
PITCH = UNIT / 30
D_MAIN = 15 / 8 * UNIT
A_MAIN = D_MAIN * PITCH / (UNIT / 8)        # 12 mm
THIN_D = 50.0                                # thin-lens camera: lens -> sensor
LOCATION = np.array([0.0, 1.2, -6.0])        # m
LOOK_AT = np.array([0.0, 0.55, 0.0])

WHITE_SCENE = "#declare R18_Own_Scene = 1;\nbackground { rgb 1 }\n"


def render_scene(args, name, size, ext="png", header=None, tag=""):
    """scenes/report2018/<name>.pov at size x size into the work folder: (image, metadata)."""
    out_name = name + tag
    out = os.path.join(args.work, out_name + "." + ext)
    pt.remove_outputs(args.work, out_name, ext)
    extra = []
    if header is not None:
        inc = pt.write_text(os.path.join(args.work, out_name + "_header.inc"), header)
        extra.append("+HI" + inc)
    options = pt.LINEAR16 if ext == "png" else pt.HALF_EXR
    cmd = [args.povray, "+I" + os.path.join(SCENES, name + ".pov"), "+L" + SCENES, "+O" + out,
           "+W%d" % size, "+H%d" % size] + list(options) + extra
    run = pt.run_process(cmd, cwd=args.work, timeout=600)
    assert run.returncode == 0 and not run.timed_out and os.path.exists(out), \
        "%s did not render:\n%s" % (name, pt.tail(run.output, 20))
    return pt.load(out)[:, :, :3], pt.load_metadata(os.path.join(args.work, out_name + ".plenoptic.json"))


@pytest.fixture(scope="module")
def work(args):
    os.makedirs(args.work, exist_ok=True)
    return args


def test_the_scenes_are_there():
    # the page's set-ups (docs/report2018.md): 5 thin lenses, 4 bare arrays, 9 full cameras
    assert len([n for n in NAMES if n.startswith("thin_lens_f")]) == 5
    assert len([n for n in NAMES if n.startswith("bare_array")]) == 4
    assert {"full_d1_16", "full_d1_8", "full_d5_8", "sensor_doubled", "array_translate_x",
            "array_translate_z", "array_rotate_direction", "array_rotate_right",
            "microlens_f10_d5_8"} <= set(NAMES)


@pytest.mark.parametrize("name", NAMES)
def test_every_scene_renders(work, name):
    image, meta = render_scene(work, name, 48, tag="_smoke")
    assert np.isfinite(image).all()
    assert image.max() > 0.05, "%s rendered black" % name
    # the sensor is 24 mm across whatever the size (48 mm for the doubled one)
    width = meta["sensor"]["pixel_size_mm"][0] * 48
    assert width == pytest.approx(48.0 if name == "sensor_doubled" else SENSOR, rel=1e-12)


# ------------------------------------------------------------------------------------------
# Thin-lens camera: the stock pinhole picture blurred by the thin-lens disc.

def disc_kernel(diameter_px, oversample=8):
    """A uniform disc of the given diameter (pixels), area-sampled, summing to 1."""
    r = diameter_px / 2
    n = int(math.ceil(r)) + 1
    fine = (np.arange(-n * oversample, (n + 1) * oversample) + 0.5) / oversample - 0.5
    x, y = np.meshgrid(fine, fine)
    inside = (x * x + y * y <= r * r).astype(float)
    k = inside.reshape(2 * n + 1, oversample, 2 * n + 1, oversample).sum(axis=(1, 3))
    return k / k.sum()


def stock_pinhole(args, size, margin, supersample=2):
    """POV-Ray's perspective camera at the thin lens's centre, the sensor THIN_D behind it, over
    the picture plus `margin` pixels on each side, supersampled and averaged (antialiased)."""
    total = size + 2 * margin
    half_width = (SENSOR / size) * total / 2
    scene = ('#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n#include "report2018.inc"\n'
             "camera { perspective location R18_Location look_at R18_Look_At right x up y\n"
             "  angle %.12f }\n" % math.degrees(2 * math.atan(half_width / THIN_D)))
    png = pt.render(args.povray, args.work, "stock_pinhole_%d" % size, scene,
                    total * supersample, total * supersample, extra=["+L" + SCENES])
    fine = pt.read_linear(png)
    return fine.reshape(total, supersample, total, supersample, 3).mean(axis=(1, 3))


def blurred(reference, diameter_px, margin, size):
    k = disc_kernel(diameter_px)
    out = np.stack([signal.fftconvolve(reference[:, :, c], k, mode="same") for c in range(3)], axis=2)
    return out[margin:margin + size, margin:margin + size]


def misfit(a, b):
    return float(np.sqrt(((a - b) ** 2).mean()) / a.std())


@pytest.mark.parametrize("focal", [0.05, 0.5, 5.0, 50.0, 100.0])
def test_thin_lens_is_the_pinhole_picture_blurred(work, focal):
    size, margin = 96, 36
    pixel = SENSOR / size
    ours, meta = render_scene(work, "thin_lens_f" + ("%g" % focal).replace(".", "_"), size)
    assert meta["sensor"]["pixel_size_mm"][0] * size == pytest.approx(SENSOR, rel=1e-12)
    aperture = focal / 8
    # b = A |D (1/F - 1/z) - 1| at the scene's typical distance (the sphere, 6.2 m; the plane
    # and the other objects, 3.7 to 8 m, change it by under 3 % for every lens but f = 50)
    z = 6200.0
    b = aperture * abs(THIN_D * (1 / focal - 1 / z) - 1) / pixel
    reference = stock_pinhole(work, size, margin)
    fit = misfit(ours, blurred(reference, max(b, 1e-3), margin, size))
    print("f = %g mm: b = %.2f px, misfit %.4f" % (focal, b, fit))
    if focal == 50.0:                            # b = 0.2 px: the pinhole picture itself
        assert fit < 0.08
        assert misfit(ours, blurred(reference, 6.0, margin, size)) > 2 * fit
        return
    assert fit < 0.05, "f = %g: not the pinhole picture blurred by %.1f px (misfit %.3f)" % (focal, b, fit)
    for wrong in (0.6 * b, 1.5 * b):
        assert misfit(ours, blurred(reference, wrong, margin, size)) > 2 * fit
    assert misfit(ours, reference[margin:margin + size, margin:margin + size]) > 4 * fit
    # it does not vanish: the mean is the pinhole picture's (the blur moves light, it keeps it)
    assert ours.mean() == pytest.approx(reference[margin:margin + size, margin:margin + size].mean(), rel=0.05)


# ------------------------------------------------------------------------------------------
# Bare array tilted by 20 degrees: black exactly where the array would be behind the sensor.

@pytest.mark.parametrize("name,axis", [("bare_array_rotate_right", "rows"), ("bare_array_rotate_up", "columns")])
def test_tilted_bare_array_is_dark_only_behind_the_sensor(work, name, axis):
    size = 240
    image, _ = render_scene(work, name, size)
    dark = image.max(axis=2) <= 0.0
    lines = dark.all(axis=1) if axis == "rows" else dark.all(axis=0)
    # the array plane is z = y tan 20 (rows) or z = -x tan 20 (columns) in the optics frame; the
    # sensor is at z = -d; the read-out puts sensor -y at the top and +x at the left
    edge_mm = (UNIT / 8) / math.tan(math.radians(20))          # 8.24 mm from the axis
    expected = (SENSOR / 2 - edge_mm) / (SENSOR / size)         # lines beyond it
    n_dark = int(lines.sum())
    assert abs(n_dark - expected) <= 1.0, (n_dark, expected)
    assert lines[:n_dark].all()                                 # they are the first lines
    rest = dark[n_dark + 1:] if axis == "rows" else dark[:, n_dark + 1:]
    assert rest.mean() < 0.01                                   # and nothing else is dark


# ------------------------------------------------------------------------------------------
# Full camera: irradiance over whole cells = flux through a lens over its microimage cell.

def cell_solid_angle(d):
    """C of an array of thin microlenses, written out (docs/camera.md, "Radiometry"): the cell's
    area times the mean of cos^4 over the cell seen from d below its centre, over d^2."""
    n = 400
    u = (np.arange(n) + 0.5) / n * PITCH - PITCH / 2
    x, y = np.meshgrid(u, u)
    cos4 = (d * d / (d * d + x * x + y * y)) ** 2
    return PITCH * PITCH * cos4.mean() / (d * d)


@pytest.mark.parametrize("name,D,d", [
    ("full_d1_16", D_MAIN, UNIT / 16),
    ("full_d1_8", D_MAIN, UNIT / 8),
    ("full_d5_8", D_MAIN, 5 * UNIT / 8),
    ("array_translate_z", D_MAIN - 0.4 * UNIT, UNIT / 8 + 0.4 * UNIT),
    ("microlens_f10_d5_8", D_MAIN, 5 * UNIT / 8),
])
def test_white_scene_irradiance_is_conserved(work, name, D, d):
    size = 240
    value, meta = render_scene(work, name, size, ext="exr", header=WHITE_SCENE, tag="_white")
    c = meta["sensor"]["radiometry"]["projected_solid_angle_sr"]
    assert c == pytest.approx(cell_solid_angle(d), rel=1e-4)
    irradiance = value[:, :, 1] * c                  # E for radiance 1
    # a window of whole microimage cells (pitch p (1 + d/D) on the sensor) around the axis
    cell_px = PITCH * (1 + d / D) / (SENSOR / size)
    centre = size / 2
    lo, hi = int(round(centre - 3 * cell_px)), int(round(centre + 3 * cell_px))
    mean = irradiance[lo:hi, lo:hi].mean()
    a = A_MAIN / 2
    expected = math.pi * a * a / (D * D + a * a) / (1 + d / D) ** 2
    print("%s: mean E %.5f, expected %.5f (window %d px, cell %.2f px)" % (name, mean, expected, hi - lo, cell_px))
    assert mean == pytest.approx(expected, rel=0.03)


# ------------------------------------------------------------------------------------------
# Symmetries the page states.

def test_translation_by_whole_pitches_changes_nothing(work):
    a, _ = render_scene(work, "full_d1_8", 120)
    b, meta = render_scene(work, "array_translate_x", 120)
    assert meta["microlens_array"]["translate_mm"][0] == pytest.approx(0.4 * UNIT)
    assert np.abs(a - b).max() < 2e-3, np.abs(a - b).max()
    # the control: half a pitch more moves every microimage by half a cell
    c, meta = render_scene(work, "array_translate_x", 120, header="#declare R18_Translate_X = 0.4 + 1/60;\n",
                           tag="_half_pitch")
    assert meta["microlens_array"]["translate_mm"][0] == pytest.approx((0.4 + 1 / 60) * UNIT)
    assert misfit(a, c) > 0.5, misfit(a, c)


def test_doubled_sensor_centre_is_the_raw_binned(work):
    size = 192
    normal, _ = render_scene(work, "full_d1_8", size, ext="exr", tag="_192")
    doubled, _ = render_scene(work, "sensor_doubled", size, ext="exr")
    binned = normal.reshape(size // 2, 2, size // 2, 2, 3).mean(axis=(1, 3))
    centre = doubled[size // 4:size // 4 + size // 2, size // 4:size // 4 + size // 2]
    fit = misfit(binned, centre)
    shifted = misfit(binned, doubled[size // 4 + 1:size // 4 + 1 + size // 2, size // 4:size // 4 + size // 2])
    print("binned vs doubled centre: misfit %.4f (one pixel off: %.4f)" % (fit, shifted))
    assert fit < 0.15                # 64 samples of irradiance: about 0.1 is sampling noise
    assert shifted > 3 * fit


def srgb(linear):
    """The sRGB encoding (IEC 61966-2-1), clipped to [0, 1]."""
    x = np.clip(linear, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def test_figure_tool_writes_the_figures(work):
    """tools/report2018-figures (the page's figures): every PNG written, the reference scene at
    E / C_ref = its own E / C, a refused scene name refused."""
    out = os.path.join(work.work, "figures")
    tool = os.path.join(work.tools, "report2018-figures")
    run = pt.run_process([sys.executable, tool, "--povray", work.povray, "--out", out, "--size", "48",
                          "--only", "full_d1_16", "thin_lens_f50"], timeout=600)
    assert run.returncode == 0, run.output
    for name in ("full_d1_8", "full_d1_8_zoom", "full_d1_16", "full_d1_16_zoom", "thin_lens_f50"):
        assert pt.load(os.path.join(out, name + ".png")).shape[:2] == ((192, 192) if "zoom" in name else (48, 48))  # zoom: all 48 px, x4
    assert not os.path.exists(os.path.join(out, "thin_lens_f50_zoom.png"))   # no array, no zoom
    assert not os.path.exists(os.path.join(out, ".work"))
    # the reference is shown at its own exposure: the sRGB PNG of its linear render
    linear, _ = render_scene(work, "full_d1_8", 48, ext="exr", tag="_48")
    shown = pt.load(os.path.join(out, "full_d1_8.png"))
    assert np.abs(shown - srgb(linear)).max() < 0.01      # half-float EXR and 8-bit rounding
    # another array scene is shown at the reference's exposure: its E / C times C / C_ref
    other, other_meta = render_scene(work, "full_d1_16", 48, ext="exr", tag="_48")
    _, ref_meta = render_scene(work, "full_d1_8", 48, ext="exr", tag="_48")
    scale = (other_meta["sensor"]["radiometry"]["projected_solid_angle_sr"]
             / ref_meta["sensor"]["radiometry"]["projected_solid_angle_sr"])
    assert scale == pytest.approx(cell_solid_angle(UNIT / 16) / cell_solid_angle(UNIT / 8), rel=1e-4)
    assert np.abs(pt.load(os.path.join(out, "full_d1_16.png")) - srgb(other * scale)).max() < 0.01
    bad = pt.run_process([sys.executable, tool, "--povray", work.povray, "--out", out, "--only", "no_such"])
    assert bad.returncode != 0 and "no such scene: no_such" in bad.output
