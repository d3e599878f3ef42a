# SPDX-License-Identifier: AGPL-3.0-or-later
"""Bare pinhole array (no main lens): each microimage is a pinhole camera at its lens.

docs/specification.md, section 3: with no main lens, a pixel belongs to the lens straight above it,
and its ray runs from the pixel through that lens's centre. So:

1. Rectangular array whose cells cover whole blocks of n x n pixels: the block under
   lens c must be, pixel for pixel, the stock perspective camera at c (same axes) with
   an n x n image and angle 2 atan(n sx / 2d). The scene is scaled so that one scene
   unit is one millimetre (mm_per_unit 1): neighbouring lenses then see the scene with
   a large parallax, so a block rendered from the wrong lens cannot pass.
2. Hexagonal arrays (one plain, one rotated about z and translated): small emissive
   discs parallel to the sensor image, through each lens centre c, to the point
   c + (c - X) d / X_z (a disc parallel to the sensor projects to a circle centred
   there). The test predicts every image of every disc from the lattice and pose of
   docs/specification.md (section 2), measures the centroids of the blobs in the
   render, and compares; it also checks that exactly the predicted lenses show each disc.
"""
import glob
import math
import os

import numpy as np
import pytest

import plenoptic_testing as pt

LOC = np.array([0.1, 0.65, -3.0])   # scene units = mm here
v3 = lambda a: "<%.17g, %.17g, %.17g>" % tuple(a)


def test_rectangular_array_blocks(args):
    n, sx, d = 16, 0.01, 0.22
    p = n * sx
    W, H = 8 * n, 6 * n
    scene = pt.TEXTURED_SCENE
    plen = ("camera { plenoptic location %s mm_per_unit 1\n"
            "  microlens_array { rectangular pitch %r pinhole distance %r }\n"
            "  sensor { pixel_size %r } }\n" % (v3(LOC), p, d, sx))
    img = pt.load(pt.render(args.povray, args.work, "rect_array", scene + plen, W, H))
    # Lenses whose n x n block lies wholly inside the image: block of lens (k, l) starts at
    # column W/2 - (k + 1/2) n (x grows to the left) and row H/2 + (l - 1/2) n (y grows down).
    lenses = []
    for l in range(-3, 4):
        for k in range(-4, 5):
            i0 = W // 2 - k * n - n // 2
            j0 = H // 2 + l * n - n // 2
            if 0 <= i0 and i0 + n <= W and 0 <= j0 and j0 + n <= H:
                lenses.append((k, l, i0, j0))
    angle = 2 * math.degrees(math.atan(n * sx / (2 * d)))
    locs = ", ".join(v3(LOC + np.array([k * p, l * p, 0.0])) for k, l, _, _ in lenses)
    stock = ("#declare Lens = array[%d] { %s };\n"
             "camera { perspective location Lens[frame_number] right x up y angle %.17g }\n"
             % (len(lenses), locs, angle))
    stem = os.path.join(args.work, "rect_stock")
    for old in glob.glob(stem + "*.png"):
        os.remove(old)
    pt.render(args.povray, args.work, "rect_stock", scene + stock, n, n,
                  extra=["+KFI0", "+KFF%d" % (len(lenses) - 1)])
    digits = len(str(len(lenses) - 1))
    worst = (0, None)
    bad = 0
    for idx, (k, l, i0, j0) in enumerate(lenses):
        ref = pt.load("%s%0*d.png" % (stem, digits, idx))
        block = img[j0:j0 + n, i0:i0 + n]
        diff = float(np.abs(block - ref).max())
        differing = int((np.abs(block - ref).max(axis=2) > 0).sum())
        if differing:
            bad += 1
        if diff >= worst[0]:
            worst = (diff, (k, l, differing))
    assert (bad == 0), ("rectangular array: block under each lens == stock camera at the lens" + ": " + ("%d lenses compared (n=%d px, pitch %g mm, d %g mm, angle %.4f deg); %d differ; "
                 "largest |diff| %.3g at lens %s (expected 0)" % (len(lenses), n, p, d, angle, bad,
                                                               worst[0], worst[1])))
    # The same blocks must differ between lenses (parallax), or the comparison proves nothing.
    a = img[lenses[0][3]:lenses[0][3] + n, lenses[0][2]:lenses[0][2] + n]
    b = img[lenses[-1][3]:lenses[-1][3] + n, lenses[-1][2]:lenses[-1][2] + n]
    assert float(np.abs(a - b).mean()) > 0.02, "rectangular array: lenses see different views" + ": " + ("mean |first block - last block| = %.3f (must be clearly non-zero)" % float(np.abs(a - b).mean()))


def point_scene(points, radius):
    s = ["#version 3.7;", "global_settings { assumed_gamma 1.0 }", "background { rgb 0 }"]
    for X in points:
        s.append("disc { %s, -z, %r pigment { rgb 1 } finish { ambient 1 diffuse 0 } }"
                 % (v3(LOC + X), radius))
    return "\n".join(s) + "\n"


def nearest_lens_centre(grid, pitch, q):
    """Lens (row-form index and centre) whose cell contains the array-local point q,
    by brute force over nearby lattice points (test-side, independent of the code)."""
    row = pitch * math.sqrt(3) / 2 if grid == "hexagonal" else pitch
    l0 = int(round(q[1] / row))
    best = None
    for l in range(l0 - 2, l0 + 3):
        shift = (l % 2) / 2.0 if grid == "hexagonal" else 0.0
        k0 = int(round(q[0] / pitch - shift))
        for k in range(k0 - 2, k0 + 3):
            c = pt.lattice_point(grid, pitch, k, l)
            d2 = (c[0] - q[0]) ** 2 + (c[1] - q[1]) ** 2
            if best is None or d2 < best[0]:
                best = (d2, (k, l), c)
    return best[1], best[2], math.sqrt(best[0])


@pytest.mark.parametrize("name, rotate, translate", [
    ("hex_array", [0, 0, 0], [0, 0, 0]),
    ("hex_array_posed", [0, 0, 17], [0.05, -0.08, 0.04]),
])
def test_hexagonal_array_points(args, name, rotate, translate):
    W, H = 192, 160
    sx = 0.01
    pitch, d = 0.36, 0.3
    radius = 0.12
    R = pt.rotation_xyz(rotate)
    t = np.array(translate, dtype=float)
    points = [np.array(p) for p in ([0.0, 0.0, 3.0], [0.55, -0.35, 2.4], [-0.6, 0.45, 4.0])]
    plen = ("camera { plenoptic location %s mm_per_unit 1\n"
            "  microlens_array { hexagonal pitch %r pinhole distance %r rotate %s translate %s }\n"
            "  sensor { pixel_size %r } samples 64 }\n"
            % (v3(LOC), pitch, d, v3(rotate), v3(translate), sx))
    img = pt.load(pt.render(args.povray, args.work, name, point_scene(points, radius) + plen,
                                    W, H, ext="exr"))[:, :, 0]
    sensor_z = -d  # the sensor stays at -d; a z translation moves the array only
    expected = []  # every image that may show at least in part: (u, v, radius_px, clean, lens)
    for X in points:
        for l in range(-8, 9):
            for k in range(-8, 9):
                own = pt.lattice_point("hexagonal", pitch, k, l)
                c = R @ own + t
                # Pinhole projection through the lens centre onto the sensor plane.
                s = (sensor_z - c[2]) / (c[2] - X[2])
                hit = c + s * (c - X)
                r_px = radius * (c[2] - sensor_z) / (X[2] - c[2]) / sx
                # The lens's microimage is its cell, straight below it (array-local coordinates).
                q = R.T @ (np.array([hit[0], hit[1], c[2]]) - t)
                lens, _, dist = nearest_lens_centre("hexagonal", pitch, q)
                from_own = math.hypot(q[0] - own[0], q[1] - own[1])
                if from_own / sx > pitch / math.sqrt(3) / sx + r_px + 1:
                    continue  # the disc's image cannot reach this lens's cell
                u, v = pt.sensor_to_pixel(hit[0], hit[1], W, H, sx, sx)
                # Clean: wholly inside its own cell (inradius p/2) and inside the image.
                clean = lens == (k, l) and (pitch / 2 - dist) / sx > r_px + 1.5 and \
                    r_px + 1.5 < u < W - 1 - r_px - 1.5 and r_px + 1.5 < v < H - 1 - r_px - 1.5
                if -r_px - 1 < u < W + r_px and -r_px - 1 < v < H + r_px:
                    expected.append([u, v, r_px, clean, (k, l)])
    # Images of two discs that touch in one microimage merge into one blob: not clean.
    for a in expected:
        for b in expected:
            if a is not b and a[4] == b[4] and math.hypot(a[0] - b[0], a[1] - b[1]) < a[2] + b[2] + 3:
                a[3] = False
    labels, count = pt.label_components(img > 0.01)
    blobs = pt.component_centroids(img, labels, count)
    errors = []
    missing = []
    for (u, v, r_px, clean, _) in expected:
        if not clean:
            continue
        near = [b for b in blobs if math.hypot(b["u"] - u, b["v"] - v) < r_px + 2]
        if len(near) != 1:
            missing.append((round(u, 1), round(v, 1), len(near)))
            continue
        errors.append(math.hypot(near[0]["u"] - u, near[0]["v"] - v))
    # Every blob must be one of the predicted images (clean or cut by a border).
    stray = [(round(b["u"], 1), round(b["v"], 1)) for b in blobs
             if not any(math.hypot(b["u"] - u, b["v"] - v) < r + 3 for u, v, r, _, _ in expected)]
    assert (not missing and not stray and len(errors) >= 12), (name + ": the predicted lenses show each disc" + ": " + ("%d clean predicted images found, %d missing %s, %d blobs in the render, "
                 "%d unexpected %s" % (len(errors), len(missing), missing[:5], len(blobs), len(stray), stray[:5])))
    if errors:
        e = np.array(errors)
        assert (e.mean() <= 0.05 and e.max() <= 0.15), (name + ": image positions" + ": " + ("|measured - pinhole projection| mean %.4f px, max %.4f px over %d images "
                     "(tolerance: mean 0.05, max 0.15 px)" % (e.mean(), e.max(), len(e))))

