# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode --total-focus against POV-Ray's stock perspective camera.

Scene: a Keplerian focused camera (F = 50 mm f/5.6 focused at 1 m, hexagonal microlenses of
pitch 0.15 mm, f = 0.5 mm at d = 0.75 mm) renders two self-lit textured planes, at 2.5 m (upper
half) and 5 m, with its depth map (and so its virtual depth map). The total-focus image, read
from the microimages at the virtual depth, is the picture a pinhole at the main lens's centre
takes on a sensor D + d behind it: POV-Ray's own perspective camera with
angle = 2 atan(W pixel / (2 (D + d))) renders it, and is sampled here at the total-focus image's
sample positions (a centred grid STEP pixels apart). On each (checkered) plane the normalised
cross-correlation must be high, as high as with the best constant virtual depth, higher than
with the other plane's, and gone with the sign flipped; the near plane registers best at its
thin-lens virtual depth. (The far plane's microimages carry a microlens blur of about a pixel,
magnified by |v| in the total focus: its correlation is lower, and its peak over constant depths
broad, so only the near plane's peak is located.)
"""

import math
import os
import subprocess
import sys

import numpy as np

import plenoptic_testing as pt

W, H = 480, 360
F, N_MAIN, FOCUS_M = 50.0, 5.6, 1.0
PITCH, MICRO_F, ARRAY_D, PIXEL = 0.15, 0.5, 0.75, 0.01
Z_NEAR, Z_FAR = 2.5, 5.0
STEP = 2.5

PLANES = """#declare Glow = finish { emission 1 diffuse 0 ambient 0 }
box { <-3, 0, %r>, <3, 3, %r> pigment { checker rgb <0.9, 0.8, 0.3> rgb <0.1, 0.2, 0.6> scale 0.01 } finish { Glow } }
plane { z, %r pigment { checker rgb <0.8, 0.3, 0.2> rgb <0.2, 0.7, 0.3> scale 0.03 } finish { Glow } }
""" % (Z_NEAR, Z_NEAR + 1e-4, Z_FAR)

FOCUSED = """camera {
  plenoptic location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }
  microlens_array { hexagonal pitch %r focal_length %r distance %r }
  sensor { pixel_size %r }
  samples 16
  depth_map
}
""" % (F, N_MAIN, FOCUS_M, PITCH, MICRO_F, ARRAY_D, PIXEL)


def stock_camera():
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    angle = 2 * math.degrees(math.atan(W * PIXEL / (2 * (D + ARRAY_D))))
    return "camera { perspective location <0, 0, 0> look_at <0, 0, 1> right x * %d / %d angle %r }\n" % (W, H, angle)


def virtual_depth(z_m):
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    b = F * z_m * 1000.0 / (z_m * 1000.0 - F)
    return -(D - b) / ARRAY_D


def sample_grid(step):
    columns = int(math.floor((W - 1) / step)) + 1
    rows = int(math.floor((H - 1) / step)) + 1
    x = np.arange(columns) * step + 0.5 * ((W - 1) - (columns - 1) * step)
    y = np.arange(rows) * step + 0.5 * ((H - 1) - (rows - 1) * step)
    return np.meshgrid(x, y)


def ncc(a, b):
    a = a - a.mean()
    b = b - b.mean()
    return float((a * b).sum() / math.sqrt((a * a).sum() * (b * b).sum()))


def total_focus(args, raw, out, *options):
    run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-decode"), raw, "-q", "--total-focus", out,
                          "--total-focus-step", str(STEP)] + list(options), capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, "plenoptic-decode --total-focus exits 0 (stderr: %s)" % run.stderr[-2000:]
    return pt.load(out)[..., :3]


def test_total_focus_matches_stock_perspective(args):
    raw, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "tf_focused", FOCUSED + PLANES, W, H)
    stock = pt.read_linear(pt.render_ground_truth(args.povray, args.work, "tf_stock", stock_camera() + PLANES, W, H)[0])
    stock = stock[..., :3]
    meta = pt.read_json(meta_path)
    assert meta["virtual_depth_map"], "the focused render wrote its virtual depth map"

    xs, ys = sample_grid(STEP)
    from scipy import ndimage
    reference = np.stack([ndimage.map_coordinates(stock[..., c], [ys, xs], order=1) for c in range(3)], axis=-1)
    # The upper half sees the near plane, the lower half the far one; a margin around the edge and
    # the picture's border (the outermost microimages are cut).
    near = (ys < H / 2 - 12) & (ys > 12) & (xs > 12) & (xs < W - 13)
    far = (ys > H / 2 + 12) & (ys < H - 13) & (xs > 12) & (xs < W - 13)

    image = total_focus(args, raw, os.path.join(args.work, "tf_total.exr"))
    assert image.shape[:2] == xs.shape, "total focus %s samples, the documented grid %s" % (image.shape[:2], xs.shape)
    ref_grey = reference.mean(axis=2)
    regions = (("near", near), ("far", far))
    scores = {name: ncc(image.mean(axis=2)[region], ref_grey[region]) for name, region in regions}
    # Constant virtual depths across the scene's range, and the right ones with the sign flipped.
    scan = {}
    for v in (-1.8, virtual_depth(Z_NEAR), -2.5, virtual_depth(Z_FAR), -3.2, -3.6,
              -virtual_depth(Z_NEAR), -virtual_depth(Z_FAR)):
        out = os.path.join(args.work, "tf_const_%+.3f.exr" % v)
        other = total_focus(args, raw, out, "--virtual-depth", repr(v)).mean(axis=2)
        scan[v] = {name: ncc(other[region], ref_grey[region]) for name, region in regions}
    print("total focus NCC from the virtual depth map: %s; at constant virtual depths: %s" % (
        {k: round(x, 3) for k, x in scores.items()},
        {round(v, 3): {k: round(x, 3) for k, x in r.items()} for v, r in scan.items()}))
    assert scores["near"] > 0.93 and scores["far"] > 0.7, (
        "the total focus correlates with the stock perspective render on both planes: %s" % scores)
    negative = [v for v in scan if v < 0]
    for name, z, other_z in (("near", Z_NEAR, Z_FAR), ("far", Z_FAR, Z_NEAR)):
        best = max(scan[v][name] for v in negative)
        assert scores[name] > best - 0.02, (
            "%s plane: the map's virtual depth registers it as well as the best constant one (%.3f vs %.3f)"
            % (name, scores[name], best))
        assert scan[virtual_depth(other_z)][name] < scores[name] - 0.02, (
            "%s plane: read at the other plane's virtual depth it matches worse (%.3f vs %.3f)"
            % (name, scan[virtual_depth(other_z)][name], scores[name]))
        assert scan[-virtual_depth(z)][name] < 0.4, (
            "%s plane: read with the virtual depth's sign flipped it does not match (%.3f)" % (name, scan[-virtual_depth(z)][name]))
    peak = max(negative, key=lambda v: scan[v]["near"])
    assert abs(peak - virtual_depth(Z_NEAR)) < 0.2, (
        "the near plane registers best at its thin-lens virtual depth %.3f (peak of the scan at %.3f)"
        % (virtual_depth(Z_NEAR), peak))


def test_total_focus_refusals(args):
    raw = os.path.join(args.work, "tf_focused.png")
    if not os.path.exists(raw):
        raw = pt.render_ground_truth(args.povray, args.work, "tf_focused", FOCUSED + PLANES, W, H)[0]
    for options, words in ((["--virtual-depth", "0"], "--virtual-depth"), (["--total-focus-step", "1"], "--total-focus"),
                           (["--total-focus", "x.png", "--hci", "d"], "not both")):
        run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-decode"), raw, "-q"] + options,
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 2 and words in run.stderr and "Traceback" not in run.stderr, (
            "%s: exit 2 naming %s (got %d: %s)" % (options, words, run.returncode, run.stderr))
    plenoptic1 = FOCUSED.replace("distance %r }" % ARRAY_D, "distance %r }" % MICRO_F)
    png = pt.render_ground_truth(args.povray, args.work, "tf_plenoptic1", plenoptic1 + PLANES, W, H)[0]
    run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-decode"), png, "-q", "--total-focus",
                          os.path.join(args.work, "tf_p1.png")], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and "plenoptic 1.0" in run.stderr and "Traceback" not in run.stderr, (
        "a plenoptic 1.0 raw is refused (got %d: %s)" % (run.returncode, run.stderr))
