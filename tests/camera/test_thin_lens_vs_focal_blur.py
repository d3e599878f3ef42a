# SPDX-License-Identifier: AGPL-3.0-or-later
"""Thin main lens, no array == stock perspective camera with focal_blur.

docs/specification.md, section 3: same image up to sampling noise. The stock camera gets the
pinhole-equivalent angle 2 atan(W sx / 2D) with D from 1/F = 1/z + 1/D, its
focal_point on the optical axis at the focus distance z (stock focal blur focuses on
the plane at that distance along the viewing direction, as the thin lens does), and
`aperture 2 A / mm_per_unit`: POV-Ray 3.7 scales its sample grid (radius 0.5) by
aperture/2, so its lens disc has diameter aperture/2 (tracepixel.cpp,
JitterCameraRay). A naive `aperture A` gives half the blur; the test renders that
too and requires it to fail the tolerance, which shows the comparison can tell a
wrong blur from noise.

Tolerances come from the sample counts. Each camera averages N samples per pixel,
so each image carries noise of standard deviation s_N = sigma / sqrt(N) per pixel,
and the difference of two independent N-sample images has sqrt(2) s_N. The test
measures the noise scale on the stock camera alone, as the mean absolute difference
between its N- and 4N-sample renders, whose noise is sqrt(1 + 1/4) s_N; the expected
mean absolute difference between the two cameras is then sqrt(2 / 1.25) times that.
The tolerance allows 1.5 times the expected value (the two cameras stratify their
samples differently; POV-Ray's hexagonal grid with jitter is noisier than ours, which
only lowers our side). A k x k box blur (k = 6) shrinks the noise (by up to k) while
a wrong blur radius or focus survives it; the blurred images must agree within
1.5 sqrt(2 / 1.25) times the stock camera's noise scale measured the same way, between its
blurred N- and 4N-sample renders (measured rather than divided by k, because neighbouring
pixels' noise is not independent), and no blurred pixel may differ by more than 8 times
that tolerance.
"""
import math

import numpy as np

import plenoptic_testing as pt

MM_PER_UNIT = 250.0   # a quarter-scale scene: large blur for a modest lens
LOCATION = np.array([0.15, 0.7, -3.0])
LOOK_AT = np.array([0.0, 0.45, 0.0])
F = 35.0              # mm
F_NUMBER = 1.4
W, H = 160, 120
PIXEL = 0.15          # mm
FOCUS = 1.95          # scene units: the marbled sphere's front
N = 64                # samples per pixel, both cameras
BLUR_K = 6            # box blur for the low-noise comparison


def stock_camera(aperture_units, samples):
    direction = (LOOK_AT - LOCATION) / np.linalg.norm(LOOK_AT - LOCATION)
    focal_point = LOCATION + FOCUS * direction
    D = pt.thin_lens_D(F, FOCUS * MM_PER_UNIT)
    angle = 2 * math.degrees(math.atan(W * PIXEL / (2 * D)))
    v = lambda a: "<%.17g, %.17g, %.17g>" % tuple(a)
    return ("camera { perspective location %s look_at %s right x*%r/%r up y angle %.17g\n"
            "  aperture %.17g blur_samples %d focal_point %s variance 0 }\n"
            % (v(LOCATION), v(LOOK_AT), float(W), float(H), angle, aperture_units, samples,
               v(focal_point)))


def plenoptic_camera(samples):
    v = lambda a: "<%.17g, %.17g, %.17g>" % tuple(a)
    return ("camera { plenoptic location %s look_at %s mm_per_unit %r\n"
            "  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }\n"
            "  sensor { pixel_size %r } samples %d }\n"
            % (v(LOCATION), v(LOOK_AT), MM_PER_UNIT, F, F_NUMBER, FOCUS, PIXEL, samples))


def mad(a, b):
    return float(np.abs(a - b).mean())


def test_thin_lens_vs_focal_blur(args):
    A = F / F_NUMBER
    scene = pt.TEXTURED_SCENE

    def go(name, cam):
        return pt.load(pt.render(args.povray, args.work, name, scene + cam, W, H))[:, :, :3]

    plen = go("plenoptic_n%d" % N, plenoptic_camera(N))
    stock = go("stock_n%d" % N, stock_camera(2 * A / MM_PER_UNIT, N))
    stock4 = go("stock_n%d" % (4 * N), stock_camera(2 * A / MM_PER_UNIT, 4 * N))
    naive = go("stock_naive_aperture_n%d" % N, stock_camera(A / MM_PER_UNIT, N))

    scale = math.sqrt(2 / 1.25)
    noise = mad(stock, stock4)
    expected = scale * noise
    tol = 1.5 * expected
    measured = mad(plen, stock)
    assert (measured <= tol), ("mean |plenoptic - stock|" + ": " + ("%.5f; stock noise scale (N vs 4N) %.5f -> expected %.5f from noise, tolerance %.5f"
                 % (measured, noise, expected, tol)))

    bp, bs, bs4, bn = [pt.box_blur(x, BLUR_K) for x in (plen, stock, stock4, naive)]
    bnoise = mad(bs, bs4)
    btol = 1.5 * scale * bnoise
    # A blurred image still holds pixels whose noise is not independent (neighbouring
    # pixels share texture), so the blurred noise is measured, not divided by k.
    bmeasured = mad(bp, bs)
    assert (bmeasured <= btol), ("mean |blur(plenoptic) - blur(stock)|" + ": " + ("%.5f; blurred stock noise (N vs 4N) %.5f -> tolerance %.5f (independent noise "
                 "would give %.5f)" % (bmeasured, bnoise, btol, 1.5 * scale * noise / BLUR_K)))
    worst = float(np.abs(bp - bs).max())
    wtol = 8 * btol
    assert worst <= wtol, "max |blur(plenoptic) - blur(stock)|" + ": " + ("%.4f, tolerance %.4f (8 x the mean tolerance: the tail of the noise)" % (worst, wtol))

    # The same metrics must reject the stock camera with the naive aperture (half the
    # blur): otherwise the tolerance could not tell a wrong lens from noise.
    naive_mad = mad(plen, naive)
    naive_bmad = mad(bp, bn)
    assert (naive_mad > tol and naive_bmad > btol), ("half-aperture stock camera is rejected" + ": " + ("mean |diff| %.5f (tolerance %.5f), blurred %.5f (tolerance %.5f)"
                 % (naive_mad, tol, naive_bmad, btol)))

    # Out-of-focus parts must actually be blurred: the far wall's blur disc is
    # A D |1/z - 1/z'| wide; the in-focus sphere is sharp. Compare gradient energy with
    # the same scene through a pinhole (one sample, no blur).
    D = pt.thin_lens_D(F, FOCUS * MM_PER_UNIT)
    wall_z = (3.0 - LOCATION[2]) * MM_PER_UNIT
    blur_px = A * D * abs(1 / (FOCUS * MM_PER_UNIT) - 1 / wall_z) / PIXEL
    v = lambda a: "<%.17g, %.17g, %.17g>" % tuple(a)
    sharp = go("pinhole_reference", "camera { plenoptic location %s look_at %s mm_per_unit %r "
               "main_lens { pinhole distance %.17g } sensor { pixel_size %r } }\n"
               % (v(LOCATION), v(LOOK_AT), MM_PER_UNIT, D, PIXEL))
    grad = lambda x: float((np.diff(x.mean(axis=2), axis=1) ** 2).mean())
    top = slice(0, H // 4)  # the wall fills the top quarter
    ratio = grad(plen[top]) / grad(sharp[top])
    assert (ratio < 0.5), ("far wall is blurred" + ": " + ("gradient energy of the top quarter is %.3f of the pinhole image's "
                 "(expected well below 0.5: blur disc %.1f px across)" % (ratio, blur_px)))

