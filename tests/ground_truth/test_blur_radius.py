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
  within 8 % and each within 30 %, and the same bounds must reject the moments of a blur radius
  off by 10 % either way (0.9 r and 1.1 r), so the measurement tells a 10 % wrong blur.

Noise: a spot's second moment weighs its faint outer pixels by their squared distance, so its
Monte-Carlo error grows as the spot shrinks. The near spheres' spots (moments of 75 and 9.6 px^2)
are measured at 256 samples a pixel; the far sphere's (about 1.2 px^2) at 2048, in a second
render of only the rectangle holding its images (+SC +EC +SR +ER): there the per-spot error is
about 2.5 % (its pixels' binomial standard errors, propagated; computed and printed here) where at
256 samples it reached 25 % for a spot at a microimage's rim, more than the 30 % bound allows for.
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
  samples %d
}
#macro Spot(K, L, Z)
  sphere { <-K * %r * Z / D, -L * %r * Z / D, Z>, %r pigment { rgb 1 } finish { emission 1 diffuse 0 ambient 0 } }
#end
"""


def scene(samples):
    return SCENE % (pt.thin_lens_D(F, FOCUS_M * 1000.0), F, N_MAIN, FOCUS_M, PITCH, MICRO_F, ARRAY_D, PIXEL,
                    samples, PITCH, PITCH, RADIUS_M) + "".join("Spot(%d, %d, %r)\n" % s for s in SPOTS)


# Samples a pixel per sphere (index into SPOTS): the far sphere's small spots get more.
SAMPLES, FAR_SAMPLES = 256, 2048


def libpleno_radius_px(z_m):
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    b = F * z_m * 1000.0 / (z_m * 1000.0 - F)
    a = D - b
    return 0.5 * PITCH * ARRAY_D * (1 / MICRO_F - 1 / a - 1 / ARRAY_D) / PIXEL, a, b


def window(u, v, half):
    """The pixel index ranges (inclusive) of the window around (u, v)."""
    return (max(int(math.floor(u - half)), 0), min(int(math.ceil(u + half)), W - 1),
            max(int(math.floor(v - half)), 0), min(int(math.ceil(v + half)), H - 1))


def spot_moment(image, u, v, half, samples):
    """Centroid, second moment (px^2) of the light in a window around (u, v), and that moment's
    standard error from the pixels' own: a pixel's value is the mean of `samples` samples each
    between 0 and 1 (white spheres of emission 1, sample weights at most 1), whose variance is at
    most p (1 - p) for mean p; the moment about the centroid changes by (d^2 - M) / total per unit
    of a pixel's value (the centroid's own change drops out to first order)."""
    i0, i1, j0, j1 = window(u, v, half)
    patch = image[j0:j1 + 1, i0:i1 + 1]
    jj, ii = np.mgrid[j0:j1 + 1, i0:i1 + 1]
    total = patch.sum()
    cu, cv = (patch * ii).sum() / total, (patch * jj).sum() / total
    d2 = (ii - cu) ** 2 + (jj - cv) ** 2
    moment = (patch * d2).sum() / total
    p = np.clip(patch, 0, 1)
    error = math.sqrt((((d2 - moment) ** 2) * p * (1 - p) / samples).sum()) / total
    return cu, cv, moment, error


def second_moment(r, disc_px):
    """2 r^2 / 3 + r_s^2 / 2 + 1/6: a square of half-side |r|, a disc and a pixel convolved."""
    return 2.0 / 3.0 * r ** 2 + disc_px ** 2 / 2 + 1.0 / 6.0


def moments_match(moments, predicted):
    """The test's bounds: the mean within 8 % of the prediction and each moment within 30 %."""
    mean = float(np.mean(moments))
    return abs(mean - predicted) < 0.08 * predicted and all(abs(m - predicted) < 0.3 * predicted for m in moments)


def test_blur_radius_against_spots(args):
    png, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "blur_spots", scene(SAMPLES), W, H)
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
        spots = []
        for _, k, l, u, v, r in mine:
            offset = math.hypot(k - k_spot, l - l_spot) * PITCH
            if offset + half_diagonal > 0.98 * footprint:
                continue
            if not (abs(r) + disc_px + 2 <= cell_half_px and 4 <= u <= W - 5 and 4 <= v <= H - 5):
                continue
            spots.append((k, l, u, v, abs(r) + disc_px + 2))
        assert spots, "sphere at %g m: some image through a wholly lit lens inside the picture" % z
        samples, spot_image = SAMPLES, image
        if abs(expected_r) < 2:
            # Small spots: the rectangle holding their windows again at FAR_SAMPLES (POV-Ray's
            # partial render writes the whole picture, black outside it; pixel numbers from 1).
            boxes = [window(u, v, half) for _, _, u, v, half in spots]
            region = ["+SC%d" % (min(bx[0] for bx in boxes) + 1), "+EC%d" % (max(bx[1] for bx in boxes) + 1),
                      "+SR%d" % (min(bx[2] for bx in boxes) + 1), "+ER%d" % (max(bx[3] for bx in boxes) + 1)]
            far_png, _, _ = pt.render_ground_truth(args.povray, args.work, "blur_spots_far", scene(FAR_SAMPLES), W, H,
                                                   extra=region)
            samples, spot_image = FAR_SAMPLES, pt.read_linear(far_png)[..., :3].mean(axis=2)
        moments, errors = [], []
        for k, l, u, v, half in spots:
            cu, cv, moment, error = spot_moment(spot_image, u, v, half, samples)
            assert abs(cu - u) < 0.3 and abs(cv - v) < 0.3, (
                "spot of sphere at %g m in lens (%d, %d) centred at the projection (%.2f, %.2f) vs (%.2f, %.2f)"
                % (z, k, l, cu, cv, u, v))
            moments.append(moment)
            errors.append(error)
        predicted = second_moment(expected_r, disc_px)
        mean = float(np.mean(moments))
        measured.append((z, round(expected_r, 3), samples, len(moments), round(mean, 3), round(predicted, 3),
                         [round(m, 2) for m in moments], [round(e, 3) for e in errors]))
        assert abs(mean - predicted) < 0.08 * predicted, (
            "sphere at %g m: mean spot second moment %.3f px^2 over %d lenses = 2 r^2/3 + r_s^2/2 + 1/6 = %.3f "
            "for r = %.3f px" % (z, mean, len(moments), predicted, expected_r))
        assert moments_match(moments, predicted), (
            "sphere at %g m: every spot's moment within 30 %% of %.3f: %s (standard errors %s, %d samples)"
            % (z, predicted, moments, errors, samples))
        # A blur radius 10 % off either way does not pass the same bounds.
        for wrong_r in (0.9 * expected_r, 1.1 * expected_r):
            wrong = second_moment(wrong_r, disc_px)
            assert not moments_match(moments, wrong), (
                "sphere at %g m: the moments %s also match r = %.3f px (%.3f px^2), not only r = %.3f (%.3f)"
                % (z, moments, wrong_r, wrong, expected_r, predicted))
    print("blur spots (z m, r px, samples, lenses, mean measured M2, predicted M2, each, their standard errors): %s"
          % measured)
