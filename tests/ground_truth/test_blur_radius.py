# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-project --blur against rendered spots and the thin-lens equations.

Scene: a Keplerian focused camera (F = 50 mm f/1.2 focused at 1 m, rectangular microlenses of
pitch 0.3 mm, f = 0.5 mm, d = 0.75 mm) sees three small self-lit spheres, each placed on the line
through a lens centre, at 1.3, 1.6 and 3 m. For each image of a sphere:

- the blur radius equals libpleno's r = (pitch / 2) d (1/f - 1/a - 1/d), with a = D - b and
  b = F z / (z - F), computed here;
- where the main lens's cone of light covers the lens's whole square cell (checked here from the
  footprint radius (F/N / 2) |a| / b), the rendered spot is the cell scaled to half-side |r|, the
  sphere's own disc (radius R b / z d / |a| on the sensor) and the pixel's square convolved: its
  second moment about its centroid is 2 r^2 / 3 + r_s^2 / 2 + 1/6 px^2 (moments of a square, a
  disc and a pixel add under convolution). The mean over a sphere's wholly lit images must match
  within 8 % and each within 30 % (Monte-Carlo noise of 256 samples a pixel), and, for blurs over
  2 px, differ clearly from what a blur radius off by 25 % would give.
"""

import math

import numpy as np

import plenoptic_testing as pt
from plenoptic_lf.projection import project_points

W = H = 300
F, N_MAIN, FOCUS_M = 50.0, 1.2, 1.0
PITCH, MICRO_F, ARRAY_D, PIXEL = 0.3, 0.5, 0.75, 0.01
RADIUS_M = 0.0006
SPOTS = [(0, 0, 1.3), (-3, 2, 1.6), (3, -2, 3.0)]

SCENE = """#declare D = %r;
camera {
  plenoptic location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }
  microlens_array { rectangular pitch %r focal_length %r distance %r }
  sensor { pixel_size %r }
  samples 256
}
#macro Spot(K, L, Z)
  sphere { <-K * %r * Z / D, -L * %r * Z / D, Z>, %r pigment { rgb 1 } finish { emission 1 diffuse 0 ambient 0 } }
#end
""" % (pt.thin_lens_D(F, FOCUS_M * 1000.0), F, N_MAIN, FOCUS_M, PITCH, MICRO_F, ARRAY_D, PIXEL, PITCH, PITCH, RADIUS_M) \
    + "".join("Spot(%d, %d, %r)\n" % s for s in SPOTS)


def libpleno_radius_px(z_m):
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    b = F * z_m * 1000.0 / (z_m * 1000.0 - F)
    a = D - b
    return 0.5 * PITCH * ARRAY_D * (1 / MICRO_F - 1 / a - 1 / ARRAY_D) / PIXEL, a, b


def spot_moment(image, u, v, half):
    """Centroid and second moment (px^2) of the light in a window around (u, v)."""
    i0, i1 = max(int(math.floor(u - half)), 0), min(int(math.ceil(u + half)), W - 1)
    j0, j1 = max(int(math.floor(v - half)), 0), min(int(math.ceil(v + half)), H - 1)
    patch = image[j0:j1 + 1, i0:i1 + 1]
    jj, ii = np.mgrid[j0:j1 + 1, i0:i1 + 1]
    total = patch.sum()
    cu, cv = (patch * ii).sum() / total, (patch * jj).sum() / total
    return cu, cv, (patch * ((ii - cu) ** 2 + (jj - cv) ** 2)).sum() / total


def test_blur_radius_against_spots(args):
    png, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "blur_spots", SCENE, W, H)
    image = pt.read_linear(png)[..., :3].mean(axis=2)
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    points = [(-k * PITCH * z / D, -l * PITCH * z / D, z) for k, l, z in SPOTS]
    hits = project_points(meta_path, points, tool=args.project, blur=True)
    measured = []
    for index, (k_spot, l_spot, z) in enumerate(SPOTS):
        expected_r, a, b = libpleno_radius_px(z)
        mine = [h for h in hits if h[0] == index]
        assert mine, "sphere %d images somewhere" % index
        for _, k, l, u, v, r in mine:
            assert abs(r - expected_r) < 1e-4 * max(1.0, abs(expected_r)), (
                "sphere at %g m, lens (%d, %d): blur radius %.6f px = libpleno's %.6f" % (z, k, l, r, expected_r))
        # Lenses whose whole cell the cone covers: footprint centre at the sphere's lens.
        footprint = 0.5 * F / N_MAIN * abs(a) / b
        half_diagonal = PITCH / math.sqrt(2)
        disc_px = RADIUS_M * 1000.0 * (b / (z * 1000.0)) * (ARRAY_D / abs(a)) / PIXEL
        cell_half_px = 0.5 * PITCH / PIXEL * (1 + ARRAY_D / D)  # a microimage cell's half-width
        moments = []
        for _, k, l, u, v, r in mine:
            offset = math.hypot(k - k_spot, l - l_spot) * PITCH
            if offset + half_diagonal > 0.98 * footprint:
                continue
            if not (abs(r) + disc_px + 2 <= cell_half_px and 4 <= u <= W - 5 and 4 <= v <= H - 5):
                continue
            cu, cv, moment = spot_moment(image, u, v, abs(r) + disc_px + 2)
            assert abs(cu - u) < 0.3 and abs(cv - v) < 0.3, (
                "spot of sphere at %g m in lens (%d, %d) centred at the projection (%.2f, %.2f) vs (%.2f, %.2f)"
                % (z, k, l, cu, cv, u, v))
            moments.append(moment)
        assert moments, "sphere at %g m: some image through a wholly lit lens inside the picture" % z
        predicted = 2.0 / 3.0 * expected_r ** 2 + disc_px ** 2 / 2 + 1.0 / 6.0
        wrong = 2.0 / 3.0 * (1.25 * expected_r) ** 2 + disc_px ** 2 / 2 + 1.0 / 6.0
        mean = float(np.mean(moments))
        measured.append((z, round(expected_r, 3), len(moments), round(mean, 3), round(predicted, 3),
                         [round(m, 2) for m in moments]))
        # Monte-Carlo noise: a small spot's moment scatters by ~20 % lens to lens (256 samples).
        assert abs(mean - predicted) < 0.08 * predicted, (
            "sphere at %g m: mean spot second moment %.3f px^2 over %d lenses = 2 r^2/3 + r_s^2/2 + 1/6 = %.3f "
            "for r = %.3f px" % (z, mean, len(moments), predicted, expected_r))
        assert all(abs(m - predicted) < 0.3 * predicted for m in moments), (
            "sphere at %g m: every spot's moment within 30 %% of %.3f: %s" % (z, predicted, moments))
        if abs(expected_r) > 2:
            assert abs(mean - predicted) < 0.4 * abs(wrong - predicted), (
                "the measurement tells r from 1.25 r (%.3f vs %.3f, measured %.3f)" % (predicted, wrong, mean))
    print("blur spots (z m, r px, lenses, mean measured M2, predicted M2, each): %s" % measured)
