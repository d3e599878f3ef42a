# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode RAW --hci DIR against the thin-lens geometry and the HCI benchmark's
conventions (docs/hci-export.md).

Scene: a plenoptic 1.0 camera (F = 50 mm f/2 focused at 1 m, microlenses at d = f) looks along
+z at two textured, self-lit fronto-parallel planes: a near one at z = 0.6 m on the left half,
a far one at z = 2 m behind. For hexagonal and rectangular arrays:

- the files: N x N views input_Cam000.png.. of one size, parameters.cfg with the benchmark's
  sections and keys, PFM files by netpbm's rules (read here by a reader of our own);
- gt_depth_lowres.pfm holds 0.6 and 2.0 (metres) on the planes;
- gt_disp_lowres.pfm holds, on each plane, the disparity the thin-lens equations give, computed
  here from the scene's numbers: the views are pinhole cameras at main-lens points
  pixel * D / d apart whose image plane is the focus plane, with a focal length of D / pitch
  view pixels, so disp = (pixel D / d) (D / pitch) (1/Z - 1/z0);
- the toolkit's own depth2disp (evaluation-toolkit, BaseScene.depth2disp, written out below)
  turns our depth and parameters.cfg into our disparity: its evaluation scripts read the same
  numbers;
- photo-consistency: every outer view, warped onto the centre view by the ground-truth disparity
  with the benchmark's sign (a point at x in the centre view is at x - disp (j - c) in view
  column j), matches the centre view where the outer view sees the same surface (its own depth
  map says so), and several times better than unwarped or with the sign flipped;
- --hci-all-views writes every view's disparity; an outer view's disparity warped the same way
  agrees with the centre's on the planes;
- refusals: no depth map, a focused (2.0) camera, a turned array, a square grid of views larger
  than fits.
"""

import configparser
import os
import subprocess
import sys

import numpy as np
from PIL import Image
from scipy import ndimage

import plenoptic_testing as pt

W, H = 480, 360
F, N_MAIN, FOCUS_M = 50.0, 2.0, 1.0
PITCH, MICRO_F, PIXEL = 0.14, 0.28, 0.01
Z_NEAR, Z_FAR = 0.6, 2.0

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
box   { <-1, -1, %r>, <0, 1, %r> texture { Tex scale 0.01 } }
plane { z, %r texture { Tex scale 0.03 } }
""" % (F, N_MAIN, FOCUS_M, PITCH, MICRO_F, MICRO_F, PIXEL, Z_NEAR, Z_NEAR + 1e-4, Z_FAR)

TOOLKIT_KEYS = {
    "intrinsics": ["focal_length_mm", "image_resolution_x_px", "image_resolution_y_px", "sensor_size_mm", "fstop"],
    "extrinsics": ["num_cams_x", "num_cams_y", "baseline_mm", "focus_distance_m", "center_cam_x_m",
                   "center_cam_y_m", "center_cam_z_m", "center_cam_rx_rad", "center_cam_ry_rad", "center_cam_rz_rad"],
    "meta": ["scene", "category", "date", "version", "authors", "contact", "cycles_seed", "disp_min", "disp_max",
             "frustum_disp_min", "frustum_disp_max", "depth_map_scale"],
}


def read_pfm(path):
    """netpbm's PFM: 'Pf' (grey), 'width height', scale (negative: little-endian), rows bottom first."""
    with open(path, "rb") as f:
        assert f.readline().strip() == b"Pf", "%s: not a grey PFM" % path
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        values = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    assert values.size == width * height, "%s: %d values for %d x %d" % (path, values.size, width, height)
    return values.reshape(height, width)[::-1].astype(np.float64)


def expected_disparity(z_m):
    """Thin-lens answer: views pixel * D / d apart, focal length D / pitch view pixels."""
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    baseline = PIXEL * D / MICRO_F
    return baseline * (D / PITCH) * (1.0 / (z_m * 1000.0) - 1.0 / (FOCUS_M * 1000.0))


def toolkit_depth2disp(depth_m, cfg):
    """BaseScene.depth2disp of the benchmark's evaluation toolkit, with its parameters.cfg reading."""
    width = int(cfg.get("intrinsics", "image_resolution_x_px"))
    height = int(cfg.get("intrinsics", "image_resolution_y_px"))
    focal_length_mm = float(cfg.get("intrinsics", "focal_length_mm"))
    sensor_mm = float(cfg.get("intrinsics", "sensor_size_mm"))
    baseline_mm = float(cfg.get("extrinsics", "baseline_mm"))
    focus_dist_m = float(cfg.get("extrinsics", "focus_distance_m"))
    f = (baseline_mm / 1000.) * focal_length_mm * max(width, height)
    return (f * focus_dist_m / depth_m - f) / focus_dist_m / sensor_mm


def run_decode(args, raw, *options):
    return subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-decode"), raw, "-q"] + list(options),
                          capture_output=True, text=True, timeout=300)


def render(args, name, grid, extra="depth_map"):
    png, _, _ = pt.render_ground_truth(args.povray, args.work, name, SCENE % (grid, extra), W, H)
    return png


def view(out, index):
    return np.asarray(Image.open(os.path.join(out, "input_Cam%03d.png" % index)), dtype=np.float64) / 255.0


def warp(image, dx, dy):
    """image sampled at (x + dx, y + dy) for every centre-view pixel (x, y), bilinear."""
    h, w = image.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    coords = [yy + dy, xx + dx]
    return np.stack([ndimage.map_coordinates(image[..., c], coords, order=1, mode="nearest")
                     for c in range(image.shape[2])], axis=-1)


def plane_masks(depth):
    """The pixels of each plane, away from the edge between them (two view pixels)."""
    near = np.isclose(depth, Z_NEAR, rtol=1e-5)
    far = np.isclose(depth, Z_FAR, rtol=1e-5)
    keep = ~ndimage.binary_dilation(~near, iterations=2) | ~ndimage.binary_dilation(~far, iterations=2)
    border = np.zeros_like(near)
    border[2:-2, 2:-2] = True
    return near & keep & border, far & keep & border


def check_export(args, grid):
    raw = render(args, "hci_" + grid, grid)
    out = os.path.join(args.work, "hci_" + grid)
    run = run_decode(args, raw, "--hci", out, "--hci-all-views")
    assert run.returncode == 0, "plenoptic-decode --hci exits 0 for %s (stderr: %s)" % (grid, run.stderr[-2000:])

    cfg = configparser.ConfigParser()
    cfg.read(os.path.join(out, "parameters.cfg"))
    for section, keys in TOOLKIT_KEYS.items():
        missing = [k for k in keys if not cfg.has_option(section, k)]
        assert not missing, "parameters.cfg [%s] has every key the benchmark's add-on writes (missing %s)" % (
            section, missing)
    n = int(cfg.get("extrinsics", "num_cams_x"))
    assert n == int(cfg.get("extrinsics", "num_cams_y")) and n >= 3 and n % 2 == 1, "an odd square grid: %d" % n
    width = int(cfg.get("intrinsics", "image_resolution_x_px"))
    height = int(cfg.get("intrinsics", "image_resolution_y_px"))
    names = sorted(f for f in os.listdir(out) if f.startswith("input_Cam"))
    assert names == ["input_Cam%03d.png" % i for i in range(n * n)], "views input_Cam000..%03d" % (n * n - 1)
    sizes = {Image.open(os.path.join(out, name)).size for name in names}
    assert sizes == {(width, height)}, "every view is %d x %d as parameters.cfg says: %s" % (width, height, sizes)

    depth = read_pfm(os.path.join(out, "gt_depth_lowres.pfm"))
    disparity = read_pfm(os.path.join(out, "gt_disp_lowres.pfm"))
    assert depth.shape == disparity.shape == (height, width)
    near, far = plane_masks(depth)
    assert near.sum() > 0.15 * depth.size and far.sum() > 0.15 * depth.size, (
        "both planes cover a good part of the centre view (near %d, far %d of %d px)"
        % (near.sum(), far.sum(), depth.size))
    on_planes = np.isclose(depth, Z_NEAR, rtol=1e-5) | np.isclose(depth, Z_FAR, rtol=1e-5)
    assert on_planes.all(), "every centre-view pixel sees one of the planes at 0.6 or 2 m (others: %s)" % (
        np.unique(depth[~on_planes])[:5])
    for mask, z in ((near, Z_NEAR), (far, Z_FAR)):
        expected = expected_disparity(z)
        worst = np.abs(disparity[mask] - expected).max()
        assert worst < 1e-5 * max(1.0, abs(expected)), (
            "%s: disparity on the plane at %g m is the thin-lens %.6f (worst off by %.3g)" % (grid, z, expected, worst))
    assert expected_disparity(Z_NEAR) > 0 > expected_disparity(Z_FAR), "near: positive, far: negative"
    toolkit = toolkit_depth2disp(depth, cfg)
    assert np.allclose(toolkit, disparity, rtol=1e-5, atol=1e-6), (
        "the toolkit's depth2disp on our depth and parameters.cfg gives our disparity (worst %.3g)"
        % np.abs(toolkit - disparity).max())

    # Photo-consistency, centre view against every outer view on the grid's edge and diagonal.
    c = n // 2
    centre = view(out, c * n + c)
    inside = np.zeros(depth.shape, bool)
    inside[3:-3, 3:-3] = True
    results = []
    for i, j in [(c, 0), (c, n - 1), (0, c), (n - 1, c), (0, 0), (n - 1, n - 1)]:
        outer = view(out, i * n + j)
        # Pixels the outer view sees too: where it sees, at the warped place, the depth the centre
        # view sees (its own depth map, read at the nearest pixel), at least a pixel inside.
        dx, dy = -disparity * (j - c), -disparity * (i - c)
        outer_depth = read_pfm(os.path.join(out, "gt_depth_lowres_Cam%03d.pfm" % (i * n + j)))
        yy, xx = np.mgrid[0:height, 0:width]
        seen = outer_depth[np.clip(np.rint(yy + dy), 0, height - 1).astype(int),
                           np.clip(np.rint(xx + dx), 0, width - 1).astype(int)]
        visible = inside & ~ndimage.binary_dilation(~np.isclose(seen, depth, rtol=1e-5), iterations=1)
        assert visible.sum() > 0.5 * inside.sum(), "view (%d, %d) sees most of the centre view" % (i, j)
        rms = {}
        for sign in (1, 0, -1):
            moved = warp(outer, sign * dx, sign * dy)
            rms[sign] = np.sqrt(np.mean((moved - centre)[visible] ** 2))
        results.append(((i, j), rms))
        assert rms[1] < 0.025 and rms[1] < 0.45 * min(rms[0], rms[-1]), (
            "%s: view (%d, %d) warped by the ground-truth disparity matches the centre view (rms %.4f), far "
            "better than unwarped (%.4f) or with the sign flipped (%.4f)" % (grid, i, j, rms[1], rms[0], rms[-1]))

    # Another view's own disparity: its planes at the same disparities, where that view sees them.
    corner = read_pfm(os.path.join(out, "gt_disp_lowres_Cam%03d.pfm" % 0))
    corner_depth = read_pfm(os.path.join(out, "gt_depth_lowres_Cam%03d.pfm" % 0))
    for z in (Z_NEAR, Z_FAR):
        mask = np.isclose(corner_depth, z, rtol=1e-5)
        assert mask.sum() > 0.1 * mask.size and np.allclose(corner[mask], expected_disparity(z), atol=1e-5), (
            "view 0's own disparity map holds the plane at %g m at its disparity" % z)
    # The near plane's edge moves in view 0 as the disparity says: left edge of the near region.
    shift = (np.isclose(corner_depth, Z_NEAR, rtol=1e-5).sum(axis=1) - near_count(depth)).mean()
    return n, results, shift


def near_count(depth):
    return np.isclose(depth, Z_NEAR, rtol=1e-5).sum(axis=1)


def test_hci_export(args):
    for grid in ("hexagonal", "rectangular"):
        n, results, shift = check_export(args, grid)
        # View 0 sits at the top left (j - c = -c): the near plane (left half, positive disparity)
        # moves right by c * disparity, so each row sees that much more of it.
        expected = (n // 2) * expected_disparity(Z_NEAR)
        assert abs(shift - expected) < 0.75, (
            "%s: the near plane's edge in view 0 is %.2f px further right than in the centre view, about "
            "c * disp = %.2f" % (grid, shift, expected))
        print("%s: %d x %d views; warp rms %s; near-edge shift %.2f (expected %.2f)" % (
            grid, n, n, ["%s %.4f/%.4f/%.4f" % (ij, r[1], r[0], r[-1]) for ij, r in results], shift, expected))


def test_hci_refusals(args):
    raw = render(args, "hci_nodepth", "hexagonal", extra="")
    run = run_decode(args, raw, "--hci", os.path.join(args.work, "hci_nodepth"))
    assert run.returncode == 2 and "depth_map" in run.stderr and "Traceback" not in run.stderr, (
        "no depth map: exit 2 naming depth_map (got %d: %s)" % (run.returncode, run.stderr))
    assert not os.path.exists(os.path.join(args.work, "hci_nodepth")), "nothing written for a refused export"

    focused = SCENE.replace("distance %r }" % MICRO_F, "distance %r }" % (1.5 * MICRO_F))
    png, _, _ = pt.render_ground_truth(args.povray, args.work, "hci_focused", focused % ("hexagonal", "depth_map"),
                                       W, H)
    run = run_decode(args, png, "--hci", os.path.join(args.work, "hci_focused"))
    assert run.returncode == 2 and "focused" in run.stderr and "Traceback" not in run.stderr, (
        "a focused camera: exit 2 saying why (got %d: %s)" % (run.returncode, run.stderr))

    turned = SCENE.replace("distance %r }" % MICRO_F, "distance %r rotate <0, 0, 5> }" % MICRO_F)
    png, _, _ = pt.render_ground_truth(args.povray, args.work, "hci_turned", turned % ("hexagonal", "depth_map"), W, H)
    run = run_decode(args, png, "--hci", os.path.join(args.work, "hci_turned"))
    assert run.returncode == 2 and "rotate" in run.stderr and "Traceback" not in run.stderr, (
        "an array turned about the axis: exit 2 saying why (got %d: %s)" % (run.returncode, run.stderr))

    raw = os.path.join(args.work, "hci_hexagonal.png")
    if not os.path.exists(raw):
        raw = render(args, "hci_hexagonal", "hexagonal")
    run = run_decode(args, raw, "--hci", os.path.join(args.work, "hci_big"), "--angular", "15")
    assert run.returncode == 2 and "at most" in run.stderr and "Traceback" not in run.stderr, (
        "15 x 15 views do not fit a 14 px microimage: exit 2 (got %d: %s)" % (run.returncode, run.stderr))
    run = run_decode(args, raw, "--hci-all-views")
    assert run.returncode == 2 and "--hci" in run.stderr, "--hci-all-views alone is refused: %s" % run.stderr
