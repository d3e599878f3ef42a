# SPDX-License-Identifier: AGPL-3.0-or-later
"""Irradiance radiometry in renders (docs/camera.md, "Radiometry").

`radiometry irradiance` makes a pixel the sensor irradiance over C. Checked in whole renders,
against answers that do not come from the camera's code:
  - a pinhole without an array is POV-Ray's stock perspective camera times cos^4 of each pixel's
    angle to the axis (written out here from the pixel's position), and equal to it on the axis;
  - the white image still equals a render of a white world, and a matched plenoptic 1.0 camera's
    microimages peak at 1 (an on-axis pixel lit through its whole cell sees L as L);
  - the metadata's C (projected_solid_angle_sr) is the cell's area times the mean of cos^4 over
    the cell seen from d below its centre, over d^2, summed here on a grid.
The unit tests (camera/radiometry_test.cpp) check the formulas pixel by pixel.
"""
import math
import os

import numpy as np

import plenoptic_testing as pt

LOCATION = (0.15, 0.7, -3.0)
LOOK_AT = (0.0, 0.45, 0.0)


def vec(a):
    return "<%.17g, %.17g, %.17g>" % tuple(a)


def test_pinhole_irradiance_is_the_perspective_camera_times_cos4(args):
    W, H, s, D = 161, 121, 0.01, 1.2  # odd: pixel (80, 60) is on the axis; the corners 39.9 degrees off it
    angle = 2 * math.degrees(math.atan(W * s / (2 * D)))
    stock = ("camera { perspective location %s look_at %s right x*%r/%r up y angle %.17g }"
             % (vec(LOCATION), vec(LOOK_AT), float(W), float(H), angle))
    plen = ("camera { plenoptic location %s look_at %s main_lens { pinhole distance %r }\n"
            "  sensor { pixel_size %r } radiometry irradiance }" % (vec(LOCATION), vec(LOOK_AT), D, s))
    a = pt.load(pt.render(args.povray, args.work, "irradiance_stock", pt.TEXTURED_SCENE + stock, W, H))[..., :3]
    path = pt.render(args.povray, args.work, "irradiance_pinhole", pt.TEXTURED_SCENE + plen, W, H)
    b = pt.load(path)[..., :3]
    x = ((np.arange(W) + 0.5) - W / 2) * s
    y = ((np.arange(H) + 0.5) - H / 2) * s
    cos2 = D * D / (D * D + x[None, :] ** 2 + y[:, None] ** 2)
    expected = a * (cos2 * cos2)[..., None]
    # Where the stock camera clipped at 1 (a highlight), the plenoptic one has the scaled-down true value.
    unclipped = (a < 1).all(axis=2)
    diff = np.abs(b - expected)[unclipped]
    print("pinhole irradiance: max |render - stock cos^4| %.3g over %d of %d unclipped pixels (1/65535 = %.3g); "
          "corner cos^4 %.3f" % (diff.max(), unclipped.sum(), W * H, 1 / 65535, cos2[0, 0] ** 2))
    assert unclipped.sum() > 0.99 * W * H
    # Both renders are quantised to 16 bits: the stock value's half step, scaled, plus this one's.
    assert diff.max() <= 1.0 / 65535 + 1e-9, diff.max()
    assert cos2[0, 0] ** 2 < 0.36  # a missing cos^4 would fail by far more than a step
    assert (b[H // 2, W // 2] == a[H // 2, W // 2]).all()  # on the axis: the stock camera
    meta = pt.metadata_of(path)
    assert meta["sensor"]["radiometry"] == {"model": "irradiance", "projected_solid_angle_sr": None, "angular_response": 0}
    pt.save_png(os.path.join(args.work, "irradiance_pinhole_view.png"), b)


def hexagon_mean_cos4(pitch, d, n=600):
    """Mean of cos^4 over a hexagonal lens cell (rows along x) seen from d below its centre."""
    x = (np.arange(n) + 0.5) / n * pitch - pitch / 2
    y = ((np.arange(n) + 0.5) / n * 2 - 1) * pitch / math.sqrt(3)
    X, Y = np.meshgrid(x, y)
    # Inside the cell: nearer the centre than the six neighbours at distance p.
    inside = np.ones_like(X, dtype=bool)
    for k in range(6):
        a = math.radians(60 * k)
        nx, ny = pitch * math.cos(a), pitch * math.sin(a)
        inside &= X * nx + Y * ny <= pitch * pitch / 2
    cos2 = d * d / (d * d + X ** 2 + Y ** 2)
    return float((cos2 ** 2)[inside].mean())


def test_white_image_under_irradiance(args):
    W, H = 120, 90
    scene = ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 1 }\n"
             "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n"
             "  main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }\n"
             "  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 } sensor { pixel_size 0.01 }\n"
             "  samples 64 radiometry irradiance white_image\n}\n")
    path = pt.render(args.povray, args.work, "irradiance_white", scene, W, H)
    rendered = pt.read_linear(path)[..., 0]
    white, scale = pt.white_image_values(os.path.splitext(path)[0] + ".white.png")
    white = white[..., 0]
    unclipped = white <= 1 - pt.white_image_step(scale)  # where neighbouring lenses' light adds above 1, the render clips
    assert np.abs(white - rendered)[unclipped].max() <= pt.white_image_step(scale)
    # f-number matched: the microimage centres see the whole cell, so they peak at L = 1; the
    # rims fall off (cos^4 within the microimage and the main pupil's edge).
    peak = rendered[30:60, 40:80].max()
    print("irradiance white image: peak %.4f, mean %.4f" % (peak, rendered.mean()))
    assert 0.99 < peak <= 1.0, peak
    meta = pt.metadata_of(path)
    assert meta["sensor"]["radiometry"]["model"] == "irradiance"
    d, pitch = 0.4, 0.1
    C = pitch * pitch * math.sqrt(3) / 2 * hexagon_mean_cos4(pitch, d) / (d * d)
    got = meta["sensor"]["radiometry"]["projected_solid_angle_sr"]
    assert abs(got / C - 1) < 1e-4, (got, C)
    pt.save_png(os.path.join(args.work, "irradiance_white_view.png"), white)
