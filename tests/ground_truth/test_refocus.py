# SPDX-License-Identifier: AGPL-3.0-or-later
"""Decoded light field of a plenoptic 1.0 render against the thin-lens equations.

Scene: two emissive textured planes facing the camera, a near one (top half of the picture) and
a far one (everywhere behind it), seen by a thin main lens focused between them and a hexagonal
array of microlenses at d = f. Decoded with the plenoptic_lf package (python/):

  - disparity: a point imaged by the main lens at b (1/F = 1/z + 1/b) moves, between
    sub-aperture views whose angular samples are du pixels apart, by
        ds = (D/b - 1) * D * s_x / (d * p) * du      lenses
    (chief rays: the pixel du off its microimage centre sees through the main lens at
    m = -du s_x D / d; the line from m through the image point meets the array at a point that
    moves by (1 - D/b) m). Measured by matching the extreme left and right views of each plane.
  - refocus: shift-and-add is sharpest at that slope, for each plane.
  - the decoder's command line writes every promised output, and its contact sheet's "near" and
    "far" panels are focused on the near and far plane.
"""

import glob
import json
import os
import subprocess
import sys

import numpy as np

import plenoptic_testing as pt

W, H = 480, 360
PIXEL = 0.01
F, N, FOCUS_MM = 50.0, 2.2, 1000.0
PITCH, MICRO_F = 0.12, 0.2526
Z_NEAR, Z_FAR = 600.0, 2000.0  # mm from the main lens

SCENE = """#declare Tex = texture {
  pigment { bozo color_map { [0 rgb <0.05, 0.1, 0.4>] [0.5 rgb <0.9, 0.9, 0.6>] [1 rgb <0.6, 0.1, 0.05>] } }
  finish { emission 1 diffuse 0 ambient 0 } }
camera {
  plenoptic
  location <0, 0, 0>
  look_at <0, 0, 1>
  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }
  microlens_array { hexagonal pitch %r focal_length %r distance %r }
  sensor { pixel_size %r }
  samples 16
}
box { <-1, 0, %r>, <1, 1, %r> texture { Tex scale 0.006 } }
plane { z, %r texture { Tex scale 0.02 } }
""" % (F, N, FOCUS_MM / 1000, PITCH, MICRO_F, MICRO_F, PIXEL, Z_NEAR / 1000, Z_NEAR / 1000 + 1e-4, Z_FAR / 1000)


def predicted_slope(z_mm):
    """Lenses per pixel of angular offset for a plane at z (see the module docstring)."""
    D = pt.image_distance(F, FOCUS_MM)
    b = pt.image_distance(F, z_mm)
    return (D / b - 1) * D * PIXEL / (MICRO_F * PITCH)


def match_shift(left, right, lo=-7.0, hi=7.0, step=0.01):
    """The shift ds minimising the mean squared difference right(s) - left(s - ds)."""
    best, best_cost = None, np.inf
    costs = []
    for ds in np.arange(lo, hi + step / 2, step):
        moved = pt.shift_rows(left, ds)
        diff = (right - moved)[:, ~np.isnan(moved[0])]
        if diff.shape[1] < 0.4 * right.shape[1]:
            costs.append(np.inf)
            continue
        cost = np.mean(diff * diff)
        costs.append(cost)
        if cost < best_cost:
            best, best_cost = ds, cost
    return best


def peak(values, xs):
    """Parabolic refinement of the maximum of sampled values."""
    i = int(np.argmax(values))
    if 0 < i < len(values) - 1:
        y0, y1, y2 = values[i - 1], values[i], values[i + 1]
        denom = y0 - 2 * y1 + y2
        offset = 0.5 * (y0 - y2) / denom if denom != 0 else 0.0
        return xs[i] + offset * (xs[1] - xs[0])
    return xs[i]


def test_refocus(args):
    import plenoptic_lf as lf_module
    png, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "refocus_planes", SCENE, W, H)
    raw = lf_module.read_raw(png, "linear")
    meta = lf_module.load_metadata(meta_path, (raw.shape[1], raw.shape[0]))
    lf = lf_module.decode(raw, meta)
    T, S, n_v, n_u, _ = lf.shape
    cv, cu = lf.centre_index()
    print("light field %s, angular offsets %s px" % (lf.shape, lf.du.tolist()))
    assert (S >= 30 and T >= 25 and n_u >= 7), ("decoded %d x %d lenses with %d x %d angular samples "
                 "(need >= 30 x 25 and >= 7)" % (S, T, n_u, n_v))

    # Lens rows of each plane: the near plane's edge (y = 0) runs through the picture's middle.
    # Which rows those are follows from the grid's position: rows above the centre are near.
    centres_v = lf.grid_position(np.zeros(T), np.arange(T))[:, 1]
    near_rows = centres_v < H / 2 - 3 * np.hypot(*lf.R)
    far_rows = centres_v > H / 2 + 3 * np.hypot(*lf.R)
    usable = [iu for iu in range(n_u) if lf.mask[cv, iu]]
    left, right = usable[0], usable[-1]
    baseline = (lf.du[right] - lf.du[left]) / lf.step
    slopes = np.linspace(-1.0, 1.0, 81)
    refocused = [lf_module.gray(lf.refocus(s)) for s in slopes]
    margin = 3
    for name, rows, z in (("near plane", near_rows, Z_NEAR), ("far plane", far_rows, Z_FAR)):
        expected = predicted_slope(z)
        views = [lf_module.gray(lf.view(cv, iu))[rows] for iu in (left, right)]
        ds = match_shift(views[0], views[1])
        measured = ds / baseline
        # Tolerance: 3% of the slope plus a tenth of a lens over the baseline (view matching).
        tolerance = 0.03 * abs(expected) + 0.1 / baseline
        assert (ds is not None and abs(measured - expected) <= tolerance), ("%s (z = %g mm): disparity between views u = %+g and %+g px: %.3f lenses = slope %.4f; "
                     "thin-lens prediction %.4f (tolerance %.4f)"
                     % (name, z, lf.du[left], lf.du[right], ds, measured, expected, tolerance))
        sharpness = np.array([lf_module.laplacian_energy(im)[rows][:, margin:-margin].mean() for im in refocused])
        best = peak(sharpness, slopes)
        # A sharpness peak cannot tell slopes apart that misalign the outermost views by less than
        # about a quarter of a lens (the images hardly differ): tolerance 0.25 lens / max |du|.
        tolerance = 0.25 / (np.abs(lf.du[usable]).max() / lf.step)
        assert (abs(best - expected) <= tolerance), ("%s: refocus sweep sharpest at slope %.4f; prediction %.4f (tolerance %.4f)"
                     % (name, best, expected, tolerance))
        in_focus = lf_module.laplacian_energy(lf.refocus(expected))[rows].mean()
        at_zero = lf_module.laplacian_energy(lf.refocus(0.0))[rows].mean()
        assert (in_focus > 1.5 * at_zero), ("%s: refocused at the predicted slope it is %.2f times as sharp "
                     "as at slope 0 (need > 1.5)" % (name, in_focus / max(at_zero, 1e-12)))

    # The command-line decoder on the same render: every output it promises.
    out = os.path.join(args.work, "refocus_planes.lightfield")
    run = subprocess.run(pt.decoder(args.tools) + [png, "-o", out,
                          "--encoding", "linear"], capture_output=True, text=True)
    assert (run.returncode == 0), ("plenoptic-decode exits 0 (got %d; stderr: %s)"
                 % (run.returncode, run.stderr.strip()[-500:]))
    if run.returncode == 0:
        description = json.load(open(os.path.join(out, "lightfield.json")))
        views = glob.glob(os.path.join(out, "views", "*.png"))
        refocus = glob.glob(os.path.join(out, "refocus", "*.png"))
        expected_files = ["contact_sheet.png", "views_mosaic.png", "epi.png", "refocus.gif", "lightfield.npy"]
        missing = [f for f in expected_files if not os.path.exists(os.path.join(out, f))]
        assert (not missing and len(views) == int(lf.mask.sum()) and len(refocus) == len(description["slopes"])), ("decoder wrote %s, %d views (usable angular samples: %d), %d refocus PNGs (%d slopes); missing: %s"
                     % (expected_files, len(views), int(lf.mask.sum()), len(refocus), len(description["slopes"]),
                        missing))
        stored = np.load(os.path.join(out, "lightfield.npy"))
        assert (stored.shape == lf.shape and np.abs(stored - lf.data).max() < 1e-5), "lightfield.npy %s equals the module's decode %s" % (stored.shape, lf.shape)
        from PIL import Image
        sheet = Image.open(os.path.join(out, "contact_sheet.png"))
        assert (sheet.size[0] >= 1000 and sheet.size[1] >= 400), "contact sheet is %d x %d px" % sheet.size
        near_i, far_i = description["near_far_slope_index"]
        sweep = description["slopes"]
        step = sweep[1] - sweep[0]
        assert (abs(sweep[near_i] - predicted_slope(Z_NEAR)) <= step
                     and abs(sweep[far_i] - predicted_slope(Z_FAR)) <= step), ("contact sheet's near/far panels use slopes %.3f / %.3f; the planes' slopes are %.3f / %.3f "
                     "(within one sweep step %.3f)" % (sweep[near_i], sweep[far_i], predicted_slope(Z_NEAR),
                                                       predicted_slope(Z_FAR), step))
        distances = description["slope_distances"]
        assert (distances[near_i] is not None and distances[far_i] is not None
                     and distances[near_i] < 1.0 < distances[far_i]), ("the near panel is labelled nearer than the focus distance 1 and the far one farther: %s / %s"
                     % (distances[near_i], distances[far_i]))

