# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-export RENDER --to views DIR against the thin-lens geometry and its own stated
convention (docs/export/views.md).

Scene: a plenoptic 1.0 camera (F = 50 mm f/2 focused at 1 m, microlenses at d = f, a
rectangular and a hexagonal array) looks along +z at one textured, self-lit plane at z = 0.8 m.

- Disparity of the plane, worked out here from the thin lens and the virtual depth: the main lens
  images the plane at b = F Z / (Z - F) behind it, a = D - b in front of the array (a < 0: behind
  it); a pixel du off its microimage centre (the lens centre's projection from the main lens,
  m = c (D + d) / D) sees through lens c along the ray that meets the image plane at
  c - (c d / D + du) a / d, so the point lies under lens c = (P + du a / d) D / b: it moves
  a D / (d b) x pixel / pitch lenses per pixel of du, and by the stated sign
  (x' = x - disp (j' - j)) disp = -(a / d) (D / b) (pixel step / pitch). Every disparity map holds
  it on the plane within 1e-4 px.
- Photo-consistency: a neighbouring view and the outermost view of the centre row and column,
  shifted by the stated disparity, match the reference view; the best shift found by a scan is
  within 0.05 px of the stated one (correlation of a textured plane), and the residual there is
  a third or less of the unshifted one.
- PFM: the files follow netpbm's PFM (read here by a reader of our own); the exporter's writer
  round-trips float32 bit-exactly (NaN, infinities, -0, subnormals), and an exported disparity
  file rewritten from its read values is the same bytes.
- views.json and README.md state units, sign, offset and reference view.
- A render without a depth map is refused, and so is a focused (2.0) camera (by eslf too);
  nothing is written. Ctrl-C while views are written stops the command within seconds (status
  130) and leaves nothing.
"""
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
from scipy import ndimage

import plenoptic_testing as pt

W, H = 480, 360
F, N_MAIN, FOCUS_M = 50.0, 2.0, 1.0
PITCH, MICRO_F, PIXEL = 0.07, 0.14, 0.01
Z_PLANE = 0.8

SCENE = """#declare Tex = texture {
  pigment { bozo color_map { [0 rgb <0.05, 0.1, 0.4>] [0.5 rgb <0.9, 0.9, 0.6>] [1 rgb <0.6, 0.1, 0.05>] } }
  finish { emission 1 diffuse 0 ambient 0 } }
camera {
  plenoptic
  location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }
  microlens_array { %%s pitch %r focal_length %r distance %r }
  sensor { pixel_size %r }
  samples 16
  %%s
}
plane { z, %r texture { Tex scale 0.012 } }
""" % (F, N_MAIN, FOCUS_M, PITCH, MICRO_F, MICRO_F, PIXEL, Z_PLANE)


def run_export(args, *argv):
    return subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-export"), *argv],
                          capture_output=True, text=True, timeout=300)


def read_pfm(path):
    """netpbm's PFM: 'PF' (RGB) or 'Pf' (grey), 'width height', a scale whose sign is the byte
    order (negative: little-endian), float32 rows from the bottom up."""
    with open(path, "rb") as f:
        magic = f.readline().rstrip(b"\n")
        width, height = (int(x) for x in f.readline().split())
        scale = float(f.readline())
        data = f.read()
    channels = {b"PF": 3, b"Pf": 1}[magic]
    assert len(data) == 4 * width * height * channels, "%s: %d bytes of values" % (path, len(data))
    values = np.frombuffer(data, dtype="<f4" if scale < 0 else ">f4").reshape(height, width, channels)[::-1]
    return values if channels == 3 else values[..., 0]


def expected_disparity(z_mm, step=1.0):
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    b = z_mm * F / (z_mm - F)
    a = D - b
    return -(a / MICRO_F) * (D / b) * (PIXEL * step / PITCH)


@pytest.fixture(scope="module", params=["rectangular", "hexagonal"])
def export(args, request):
    grid = request.param
    png, _, _ = pt.render_ground_truth(args.povray, args.work, "views_" + grid, SCENE % (grid, "depth_map"), W, H)
    folder = os.path.join(args.work, "views_%s_out" % grid)
    run = run_export(args, png, "--to", "views", folder, "-q")
    assert run.returncode == 0, "plenoptic-export --to views exits 0: %s" % run.stderr[-2000:]
    with open(os.path.join(folder, "views.json"), encoding="utf-8") as f:
        doc = json.load(f)
    return png, folder, doc, run.stdout.split()


def test_files_and_convention(args, export):
    _, folder, doc, listed = export
    names = sorted(os.listdir(folder))
    assert sorted(os.path.basename(p) for p in listed) == names, "stdout lists every file written"
    views = doc["views"]
    assert len(views) >= 9 and "README.md" in names
    for v in views:
        assert v["image"] in names and v["disparity"] in names
    centre = doc["reference_view"]
    assert any(v["row"] == centre["row"] and v["column"] == centre["column"] and v["offset_px"] == [0.0, 0.0]
               for v in views), "the reference view is the centre view"
    convention = doc["convention"]
    assert "x - d (j' - j)" in convention["sign"] and convention["offset"].startswith("none")
    assert convention["units"].startswith("view pixels per view step")
    with open(os.path.join(folder, "README.md"), encoding="utf-8") as f:
        readme = f.read()
    for words in ("Units:", "Sign:", "Offset: none", "Reference view:", "PFM"):
        assert words in readme, "README.md states %r" % words


def test_disparity_of_the_plane_is_the_thin_lens_answer(args, export):
    _, folder, doc, _ = export
    expected = expected_disparity(Z_PLANE * 1000.0)
    assert 0.3 < abs(expected) < 2.0, "the plane is far enough from focus to move between views"
    for v in doc["views"]:
        disparity = read_pfm(os.path.join(folder, v["disparity"]))
        inner = disparity[2:-2, 2:-2]
        assert np.isfinite(inner).all(), v["disparity"]
        worst = float(np.abs(inner - expected).max())
        assert worst < 1e-4, "%s: disparity off the thin-lens answer %.6f by up to %.3g px" % (
            v["disparity"], expected, worst)


def _residual(reference, other, shift_x, shift_y, margin):
    """Mean absolute difference between the reference view at (x, y) and `other` at
    (x - shift_x, y - shift_y) (bilinear), inside the margin."""
    h, w = reference.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    warped = np.stack([ndimage.map_coordinates(other[..., c], [yy - shift_y, xx - shift_x], order=1)
                       for c in range(3)], axis=-1)
    inner = (slice(margin, h - margin), slice(margin, w - margin))
    return float(np.abs(warped[inner] - reference[inner]).mean())


def test_shifting_a_view_by_the_disparity_aligns_it(args, export):
    _, folder, doc, _ = export
    centre = doc["reference_view"]
    by_index = {(v["row"], v["column"]): v for v in doc["views"]}
    reference = read_pfm(os.path.join(folder, by_index[centre["row"], centre["column"]]["image"])).astype(np.float64)
    stated = float(np.median(read_pfm(os.path.join(folder, by_index[centre["row"], centre["column"]]["disparity"]))))
    c = centre["column"]
    outer = max(j for (i, j) in by_index if i == centre["row"])
    for (i, j) in [(centre["row"], c + 1), (centre["row"], outer), (centre["row"] + 1, c), (outer, c)]:
        other = read_pfm(os.path.join(folder, by_index[i, j]["image"])).astype(np.float64)
        steps_x, steps_y = j - c, i - centre["row"]
        # The point at x in the reference is at x - d (j - c) in view j: sampled there, view j
        # is the reference.
        shift_x, shift_y = stated * steps_x, stated * steps_y
        margin = int(np.ceil(abs(stated) * max(abs(steps_x), abs(steps_y)))) + 3
        scan = np.linspace(-1.6, 1.6, 161) * abs(stated) * max(abs(steps_x), abs(steps_y))
        residuals = [_residual(reference, other, s if steps_x else 0.0, s if steps_y else 0.0, margin) for s in scan]
        best = float(scan[int(np.argmin(residuals))])
        expected_shift = shift_x if steps_x else shift_y
        assert abs(best - expected_shift) < 0.05, "view (%d, %d): best shift %.3f px, stated %.3f" % (
            i, j, best, expected_shift)
        aligned = _residual(reference, other, shift_x, shift_y, margin)
        unshifted = _residual(reference, other, 0.0, 0.0, margin)
        assert aligned < unshifted / 3, "view (%d, %d): residual %.4f shifted, %.4f not" % (i, j, aligned, unshifted)


def test_pfm_round_trip_is_bit_exact(args, export):
    from plenoptic_lf.export.views import write_pfm
    _, folder, doc, _ = export
    rng = np.random.default_rng(7)
    bits = rng.integers(0, 2 ** 32, size=(5, 7), dtype=np.uint64).astype(np.uint32)
    special = np.array([0x7FC00001, 0xFF800000, 0x7F800000, 0x80000000, 0x00000001, 0x007FFFFF, 0x3F800000],
                       np.uint32)
    bits[0] = special
    for values in (bits.view(np.float32), np.stack([bits.view(np.float32)] * 3, axis=-1)):
        path = os.path.join(args.work, "round_trip.pfm")
        write_pfm(path, values)
        back = read_pfm(path)
        assert back.shape == values.shape and np.array_equal(back.view(np.uint32), values.view(np.uint32)), \
            "PFM round trip changes bits"
    original = os.path.join(folder, doc["views"][0]["disparity"])
    again = os.path.join(args.work, "rewritten.pfm")
    write_pfm(again, np.ascontiguousarray(read_pfm(original)))
    with open(original, "rb") as f1, open(again, "rb") as f2:
        assert f1.read() == f2.read(), "an exported disparity file rewritten from its values is the same bytes"


def test_without_a_depth_map_it_is_refused(args):
    png, _, _ = pt.render_ground_truth(args.povray, args.work, "views_nodepth", SCENE % ("rectangular", ""), 96, 72)
    folder = os.path.join(args.work, "views_nodepth_out")
    run = run_export(args, png, "--to", "views", folder, "-q")
    assert run.returncode == 2 and "depth map" in run.stderr and len(run.stderr.strip().splitlines()) == 1, \
        run.stderr
    assert not [e for e in os.listdir(args.work) if "views_nodepth_out" in e], "nothing is written"


def test_same_numbers_as_the_hci_export(args, export):
    """The centre view's disparity is the HCI export's gt_disp_lowres.pfm of the same render
    (docs/hci-export.md): the same convention, without that layout's PNG views."""
    png, folder, doc, _ = export
    hci = folder + "_hci"
    run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-decode"), png, "-q", "--hci", hci],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    centre = doc["reference_view"]
    ours = read_pfm(os.path.join(folder, "disparity_%02d_%02d.pfm" % (centre["row"], centre["column"])))
    theirs = read_pfm(os.path.join(hci, "gt_disp_lowres.pfm"))
    assert ours.shape == theirs.shape and np.array_equal(ours, theirs), \
        "largest difference %.3g px" % float(np.abs(ours - theirs).max())


def test_a_focused_camera_is_refused(args):
    """Microlenses at d != f (plenoptic 2.0): the microimages are not sub-aperture samples; both
    view-based formats refuse and say why."""
    scene = (SCENE % ("rectangular", "depth_map")).replace("distance %r" % MICRO_F, "distance %r" % (MICRO_F * 0.6))
    assert scene != SCENE % ("rectangular", "depth_map")
    png, _, _ = pt.render_ground_truth(args.povray, args.work, "views_focused", scene, 96, 72)
    for fmt in ("views", "eslf"):
        folder = os.path.join(args.work, "views_focused_" + fmt)
        run = run_export(args, png, "--to", fmt, folder, "-q")
        assert run.returncode == 2 and "focused (2.0)" in run.stderr and "d = 0.084 mm" in run.stderr, run.stderr
        assert not [e for e in os.listdir(args.work) if os.path.basename(folder) in e], "nothing is written"


def test_ctrl_c_stops_promptly_and_leaves_nothing(args, export):
    """SIGINT (Ctrl-C) while the views are being written (many views: --step 0.25): the command
    stops within a few seconds with status 130, and neither the folder nor a staging folder is
    left."""
    import signal
    import time
    png = export[0]
    folder = export[1] + "_interrupted"
    # What an earlier run killed by a timeout (SIGKILL, which nothing can clean up after) left.
    for stale in [e for e in os.listdir(args.work) if os.path.basename(folder) in e]:
        shutil.rmtree(os.path.join(args.work, stale), ignore_errors=True)
    process = subprocess.Popen([sys.executable, os.path.join(args.tools, "plenoptic-export"), png, "--to", "views",
                                folder, "--step", "0.25"], stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        seen = []
        for line in process.stderr:
            seen.append(line)
            if line.startswith("plenoptic-export: views:"):
                break
        assert process.poll() is None, "still writing views when interrupted: %s" % "".join(seen)
        process.send_signal(signal.SIGINT)
        start = time.monotonic()
        rest = process.stderr.read()
        status = process.wait(timeout=30)
        took = time.monotonic() - start
    finally:
        if process.poll() is None:
            process.kill()
    assert status == 130 and "interrupted: nothing written" in rest, (status, rest[-1000:])
    assert took < 5, "stopped %.1f s after Ctrl-C" % took
    assert not [e for e in os.listdir(args.work) if os.path.basename(folder) in e], "nothing is left"
