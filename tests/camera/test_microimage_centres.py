# SPDX-License-Identifier: AGPL-3.0-or-later
"""Microimage centres of plenoptic cameras in a uniformly white scene.

docs/specification.md, sections 2 and 3: the centre of lens k's microimage is the central
projection of the (posed) lens centre from the main-lens centre onto the sensor at
z = -(D + d), with D from 1/F = 1/z + 1/D. Why the centroid is there: for a thin main
lens of aperture radius R, a ray from sensor point s through the cell point h of
lens c reaches the main-lens plane at m = c (1 + k) - s k + (h - c) g with k = D/d and
g = 1 + k - D/f (g = 1 + k for a pinhole lens, h = c). In a white scene the pixel at s
is lit by the fraction of h with |m| <= R; since the cell and the disc are symmetric
about their centres, that fraction is symmetric about s0 = c (1 + 1/k) = c (D + d)/D,
and so is the microimage cell (the central projection of the lens cell). Hence the
centroid of each microimage is the projection s0, whatever f and d are.

The test computes s0 for every lens from the lattice and pose of docs/specification.md (section 2)
(rotate x, y, z, then translate, then place at z = -D), renders a scene with nothing
but a white background, finds the microimages as connected bright regions, and
compares their intensity centroids with s0: mean error at most 0.1 px (the ground-truth
accuracy of docs/specification.md, section 5), no single microimage off by more than 0.25 px, and exactly
one microimage for each lens whose microimage lies inside the picture. The metadata's
microimage lattice must give the same centres to 0.01 px.
"""
import math

import numpy as np
import pytest

import plenoptic_testing as pt

W, H = 176, 132
SX = 0.006            # mm
F_MAIN = 25.0         # mm
FOCUS_M = 1.0         # scene units (metres)
F_NUMBER = 8.0
SAMPLES = 16

# (name, grid, microlens ("pinhole" or focal length mm), d mm, pitch mm, rotate deg, translate mm)
CASES = [
    ("chief_ray_hex", "hexagonal", "pinhole", 0.5, 0.12, (0, 0, 0), (0, 0, 0)),
    ("chief_ray_rect_posed", "rectangular", "pinhole", 0.5, 0.12, (0, 0, -11), (0.021, -0.034, 0.0)),
    ("plenoptic1_hex", "hexagonal", 0.5, 0.5, 0.12, (0, 0, 0), (0, 0, 0)),
    ("plenoptic1_rect", "rectangular", 0.5, 0.5, 0.12, (0, 0, 0), (0, 0, 0)),
    ("focused2_hex", "hexagonal", 0.4, 0.5, 0.12, (0, 0, 0), (0, 0, 0)),
    ("focused2_rect", "rectangular", 0.62, 0.5, 0.12, (0, 0, 0), (0, 0, 0)),
    ("focused2_hex_posed", "hexagonal", 0.4, 0.5, 0.12, (0, 0, 7.5), (0.013, -0.021, -0.02)),
    ("plenoptic1_hex_posed", "hexagonal", 0.5, 0.5, 0.12, (0, 0, 33), (-0.04, 0.027, -0.03)),
]


@pytest.mark.parametrize("name, grid, lens, d, pitch, rotate, translate", CASES, ids=[c[0] for c in CASES])
def test_microimage_centres(args, name, grid, lens, d, pitch, rotate, translate):
    lens_kw = "pinhole" if lens == "pinhole" else "focal_length %r" % lens
    scene = ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 1 }\n"
             "camera { plenoptic location <0, 0, 0>\n"
             "  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }\n"
             "  microlens_array { %s pitch %r %s distance %r rotate <%r, %r, %r> translate <%r, %r, %r> }\n"
             "  sensor { pixel_size %r } samples %d }\n"
             % ((F_MAIN, F_NUMBER, FOCUS_M, grid, pitch, lens_kw, d) + tuple(rotate) + tuple(translate)
                + (SX, SAMPLES)))
    path = pt.render(args.povray, args.work, name, scene, W, H)
    img = pt.load(path)[:, :, 0]
    lattice = pt.metadata_of(path).get("microimage_lattice") or {}

    # Expected centres, from the specification (docs/specification.md) only.
    D = pt.thin_lens_D(F_MAIN, FOCUS_M * 1000.0)
    sensor_z = -(D + d)
    A = F_MAIN / F_NUMBER
    expected = []
    for l in range(-30, 31):
        for k in range(-30, 31):
            c = pt.posed_lens_centre(grid, pitch, k, l, rotate, translate, D)
            s = sensor_z / c[2]
            u, v = pt.sensor_to_pixel(c[0] * s, c[1] * s, W, H, SX, SX)
            if -20 < u < W + 20 and -20 < v < H + 20:
                expected.append((k, l, u, v))
    # Reach of a microimage around its centre (for the border test): the aperture's image
    # A d' / D' / 2 plus the spread of a lens cell, |g| / k times its circumradius.
    D_eff = D - translate[2]
    d_eff = d + translate[2]
    kk = D_eff / d_eff
    g = 1 + kk if lens == "pinhole" else 1 + kk - D_eff / lens
    circ = pitch / math.sqrt(3) if grid == "hexagonal" else pitch / math.sqrt(2)
    reach_px = (A / 2 / kk + (0 if lens == "pinhole" else circ * abs(g) / kk)) / SX
    spacing_px = pitch * (1 + 1 / kk) / SX

    # Dilate by one pixel so that lit pixels at a microimage's sampled edge join its body.
    labels, count = pt.label_components(pt.dilate(img > 0.002, 1))
    blobs = pt.component_centroids(img, labels, count)
    inner = [b for b in blobs if b["umin"] > 0 and b["vmin"] > 0 and b["umax"] < W - 1 and b["vmax"] < H - 1]
    # A pixel that overlaps the microimage's rim at all is lit (its centre up to half a diagonal,
    # 0.71 px, beyond the reach), and the dilation adds one more pixel: 2 px of margin.
    inside = [(k, l, u, v) for k, l, u, v in expected
              if reach_px + 2 < u < W - 3 - reach_px and reach_px + 2 < v < H - 3 - reach_px]
    errors, unmatched = [], []
    for k, l, u, v in inside:
        near = [b for b in inner if math.hypot(b["u"] - u, b["v"] - v) < spacing_px / 2]
        if len(near) != 1:
            unmatched.append((k, l, len(near)))
            continue
        errors.append((math.hypot(near[0]["u"] - u, near[0]["v"] - v), near[0]["u"] - u, near[0]["v"] - v))
    stray = [(round(b["u"], 1), round(b["v"], 1)) for b in inner
             if not any(math.hypot(b["u"] - u, b["v"] - v) < spacing_px / 2 for _, _, u, v in expected)]
    assert (not unmatched and not stray and len(inside) >= 20), (name + ": one microimage per lens" + ": " + ("%d lenses with a microimage wholly inside the picture, %d bright regions clear of "
                 "the border, %d lenses without exactly one region %s, %d regions at no lens %s "
                 "(microimage radius %.1f px, spacing %.1f px)"
                 % (len(inside), len(inner), len(unmatched), unmatched[:4], len(stray), stray[:4],
                    reach_px, spacing_px)))
    # The metadata's lattice must give the same centres (it is the ground truth users read).
    if lattice.get("origin_px") and lattice.get("basis_px"):
        o = np.array(lattice["origin_px"])
        a, b = (np.array(v) for v in lattice["basis_px"])
        worst = 0.0
        for k, l, u, v in inside:
            ks = k - (l // 2) if grid == "hexagonal" else k
            worst = max(worst, float(np.hypot(*(o + ks * a + l * b - (u, v)))))
        assert (worst < 0.01), (name + ": metadata lattice" + ": " + ("largest distance between the metadata's centre and the specification's projection "
                     "%.2g px over %d lenses (tolerance 0.01 px)" % (worst, len(inside))))
    else:
        assert False, name + ": metadata lattice" + ": " + ("no microimage_lattice in the metadata")
    if errors:
        e = np.array(errors)
        assert (e[:, 0].mean() <= 0.1 and e[:, 0].max() <= 0.25), (name + ": centroids" + ": " + ("|centroid - projection| mean %.4f px, max %.4f px, mean offset (%+.4f, %+.4f) px "
                     "over %d microimages (tolerance: mean 0.1, max 0.25 px)"
                     % (e[:, 0].mean(), e[:, 0].max(), e[:, 1].mean(), e[:, 2].mean(), len(e))))

