# SPDX-License-Identifier: AGPL-3.0-or-later
"""Parametric distortion of the thin main lens:
main_lens { thin_lens ... distortion { radial <k1, k2, k3> tangential <p1, p2> } }.

The answer is computed here from the model's definition (docs/real-lenses.md, "Parametric
distortion of the thin lens"), not by the camera's code: a point in focus images where the ideal
thin lens's chief ray crosses the sensor, (x, y) = -D (X, Y) / Z, moved by the Brown-Conrady
polynomial in coordinates normalised by D. Rendered blob centroids and plenoptic-project must both
land there; the metadata must carry the coefficients; bad distortion blocks are refused.
"""
import math
import os

import numpy as np
import pytest

import plenoptic_testing as pt

F, N, FOCUS_M = 50.0, 8.0, 3.0
K = (-0.15, 0.04, 0.0)
P = (0.002, -0.003)
W, H, PIXEL = 160, 120, 0.3  # a 48 x 36 mm sensor: normalised radius up to 0.59


def distort(x, y):
    r2 = x * x + y * y
    radial = 1 + K[0] * r2 + K[1] * r2 * r2 + K[2] * r2 ** 3
    return (x * radial + 2 * P[0] * x * y + P[1] * (r2 + 2 * x * x),
            y * radial + P[0] * (r2 + 2 * y * y) + 2 * P[1] * x * y)


def scene_text(distortion, objects, extra=""):
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 0 }\n"
            "camera { plenoptic location <0, 0, -3> look_at <0, 0, 0>\n"
            "  main_lens { thin_lens focal_length %r f_number %r focus_distance %r %s }\n"
            "  sensor { pixel_size <%r, %r> } samples 100 %s\n}\n%s"
            % (F, N, FOCUS_M, distortion, PIXEL, PIXEL, extra, objects))


def test_points_land_on_the_distorted_ideal_image(args):
    D = F * FOCUS_M * 1000 / (FOCUS_M * 1000 - F)
    # A 5 x 4 grid of small spheres on the focused plane over about 80 % of the picture.
    half_x = 0.4 * W * PIXEL / D * FOCUS_M
    half_y = 0.4 * H * PIXEL / D * FOCUS_M
    points = [(x, y) for x in np.linspace(-half_x, half_x, 5) for y in np.linspace(-half_y, half_y, 4)]
    # 30 mm spheres: discs about 3.4 px across, whose centroids the pixels resolve.
    spheres = "".join("sphere { <%r, %r, 0>, 0.03 pigment { rgb 1 } finish { ambient 1 diffuse 0 } }\n" % p
                      for p in points)
    distortion = "distortion { radial <%r, %r, %r> tangential <%r, %r> }" % (K + P)
    path = pt.render(args.povray, args.work, "thin_lens_distortion", scene_text(distortion, spheres), W, H)
    metadata = os.path.join(args.work, "thin_lens_distortion.plenoptic.json")
    meta = pt.read_json(metadata)
    assert meta["main_lens"]["distortion"]["radial"] == list(K)
    assert meta["main_lens"]["distortion"]["tangential"] == list(P)
    assert abs(meta["main_lens"]["distortion"]["plane_z_mm"] + D) <= 1e-9 * D

    expected, ideal = [], []
    for x, y in points:
        # Optics frame (mm): location <0,0,-3> looking along +z; the sphere 3 m in front.
        X, Y, Z = x * 1000.0, y * 1000.0, FOCUS_M * 1000.0
        xd, yd = distort(-X / Z, -Y / Z)
        expected.append((W / 2.0 - 0.5 - xd * D / PIXEL, H / 2.0 - 0.5 + yd * D / PIXEL))
        ideal.append((W / 2.0 - 0.5 + X / Z * D / PIXEL, H / 2.0 - 0.5 - Y / Z * D / PIXEL))
    image = pt.read_linear(path)[..., :3].mean(axis=2)
    blobs = pt.blobs(image, 0.01)
    assert len(blobs) == len(points), len(blobs)
    shift = max(math.hypot(e[0] - i[0], e[1] - i[1]) for e, i in zip(expected, ideal))
    assert shift > 2, "the distortion moves the corner points by %.2f px only: the test would not see it" % shift
    errors = [min(math.hypot(b["u"] - u, b["v"] - v) for b in blobs) for u, v in expected]
    print("distorted thin lens: blob centroids within %.3f px of the formula (corner shift %.1f px)"
          % (max(errors), shift))
    assert max(errors) <= 0.1, errors

    hits = pt.run_project(args.project, metadata, [(x, y, 0.0) for x, y in points])
    assert sorted(h[0] for h in hits) == list(range(len(points))), hits
    projected = [math.hypot(u - expected[i][0], v - expected[i][1]) for i, _, _, u, v in hits]
    print("plenoptic-project: within %.2g px of the formula" % max(projected))
    assert max(projected) <= 0.01, projected


@pytest.mark.parametrize("case, block, expected", [
    ("real lens", "", "real lens has the distortion of its surfaces"),
    ("folds", "distortion { radial <-1, 0, 0> }", "folds the image over"),
    ("unknown word", "distortion { barrel 0.1 }", "radial <k1, k2, k3>, tangential <p1, p2>"),
])
def test_bad_distortion_is_refused(args, case, block, expected):
    if case == "real lens":
        main = ("prescription { surface { radius 30 thickness 6 ior 1.6 aperture 20 } stop { thickness 2 aperture 8 } "
                "surface { radius -40 thickness 0 ior 1 aperture 20 } } focus_distance 3 "
                "distortion { radial <0.1, 0, 0> }")
        scene = scene_text("", "").replace("thin_lens focal_length %r f_number %r focus_distance %r" % (F, N, FOCUS_M), main)
    else:
        scene = scene_text(block, "")
    status, output = pt.render(args.povray, args.work, "distortion_refused", scene, 16, 12, expect_failure=True)
    flat = " ".join(output.split())  # POV-Ray wraps its messages
    assert status != 0 and expected in flat, output[-1500:]
    assert "distortion" in output and "line" in output, output[-1500:]
    assert not os.path.exists(os.path.join(args.work, "distortion_refused.png"))
