# SPDX-License-Identifier: AGPL-3.0-or-later
"""Diffraction (docs/sensor.md, "Diffraction").

`diffraction` convolves the rendered picture with the Airy pattern of the aperture that forms it,
one wavelength per channel. Checked in whole renders against the Airy pattern's closed forms,
written out here from the lens's numbers (not read from the camera):
  - a point far smaller than a pixel, in focus behind a thin lens without an array, spreads so
    that 83.8 % of its light lies within 1.22 lambda N_w of its centre (Rayleigh's encircled
    energy at the first dark ring; N_w = h / (2a), the image-side working f-number), and the
    dark ring sits at that radius, larger in red than in blue by 610/465;
  - without `diffraction` the same point keeps its light within a pixel or two;
  - a white image with diffraction still equals a render of a white world, channel by channel.
"""
import math
import os

import numpy as np

import plenoptic_testing as pt

# A 50 mm f/8 thin lens focused at 2 m; pixels of 1 um, so the green Airy radius is ~5.5 pixels.
F, N, Z_MM = 50.0, 8.0, 2000.0
H_MM = F * Z_MM / (Z_MM - F)  # the sensor's distance: the image of the plane at 2 m
A_MM = F / N / 2              # the pupil's radius
WAVELENGTHS = (610.0, 550.0, 465.0)


def point_scene(diffraction):
    # The sphere (20 um at 2 m) images to a spot 1 um across: a point. It glows (emission), on black.
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 0 }\n"
            "sphere { <0, 0, 0>, 0.00002 pigment { rgb 1 } finish { emission 1 diffuse 0 ambient 0 } }\n"
            "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n"
            "  main_lens { thin_lens focal_length %r f_number %r focus_distance 2 }\n"
            "  sensor { pixel_size 0.001 } samples 64 %s }\n" % (F, N, diffraction))


def energy_within(img, radius_px):
    H, W = img.shape
    total = img.sum()
    y, x = np.mgrid[0:H, 0:W]
    cy, cx = (img * y).sum() / total, (img * x).sum() / total
    r = np.hypot(x - cx, y - cy)
    return img[r <= radius_px].sum() / total, r


def test_a_point_spreads_into_the_airy_pattern(args):
    W = H = 61
    on = pt.render(args.povray, args.work, "diffraction_point", point_scene("diffraction"), W, H)
    off = pt.render(args.povray, args.work, "diffraction_point_off", point_scene(""), W, H)
    sharp = pt.read_linear(off)[..., 1]
    blurred = pt.read_linear(on)
    n_w = H_MM / (2 * A_MM)
    radii = [1.22 * lam * 1e-6 * n_w / 0.001 for lam in WAVELENGTHS]  # pixels
    print("Airy radii (px): red %.2f green %.2f blue %.2f" % tuple(radii))
    kept, _ = energy_within(sharp, 1.5)
    assert kept > 0.99, kept  # without diffraction the point stays a point
    assert blurred[..., 1].sum() > 0.9 * sharp.sum()  # light is kept (the window holds 96 %)
    for c, radius in enumerate(radii):
        img = blurred[..., c]
        inside, r = energy_within(img, radius)
        # Rayleigh: 83.8 % within the first dark ring, of the 95.9 % the kernel's window holds.
        expected = 0.838 / 0.959
        print("channel %d: %.3f of the light within %.2f px (Airy: %.3f)" % (c, inside, radius, expected))
        assert abs(inside - expected) < 0.03, (c, inside, expected)
        # The dark ring: the radial profile's minimum between 0.6 and 1.6 Airy radii.
        bins = np.arange(0.6 * radius, 1.6 * radius, 0.25)
        profile = [img[(r >= b) & (r < b + 0.5)].mean() for b in bins]
        ring = bins[int(np.argmin(profile))] + 0.25
        assert abs(ring / radius - 1) < 0.12, (c, ring, radius)
    pt.save_png(os.path.join(args.work, "diffraction_point_view.png"), blurred / blurred.max())


def test_white_image_with_diffraction_equals_a_white_world(args):
    # Lytro-class: 14 um f/2 hexagonal microlenses at d = f, 1.4 um pixels: Airy radius ~1 pixel.
    W, H = 96, 72
    scene = ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 1 }\n"
             "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n"
             "  main_lens { thin_lens focal_length 6.45 f_number 2 focus_distance 2 }\n"
             "  microlens_array { hexagonal pitch 0.014 focal_length 0.028 distance 0.028 }\n"
             "  sensor { pixel_size 0.0014 } samples 16 radiometry irradiance diffraction white_image }\n")
    path = pt.render(args.povray, args.work, "diffraction_white", scene, W, H)
    rendered = pt.read_linear(path)
    white, scale = pt.white_image_values(os.path.splitext(path)[0] + ".white.png")
    assert white.shape == rendered.shape  # R, G, B: diffraction differs by colour
    unclipped = white <= 1 - pt.white_image_step(scale)  # above 1 the render clips
    diff = np.abs(white - rendered)[unclipped].max()
    print("white image with diffraction - render of a white world: max %.2g" % diff)
    assert diff <= pt.white_image_step(scale), diff
    assert not np.array_equal(rendered[..., 0], rendered[..., 2])  # red spreads more than blue
    meta = pt.metadata_of(path)
    d = meta["diffraction"]
    assert d["aperture"] == "microlens"
    assert abs(d["airy_radius_um"][1] - 1.22 * 0.55 * 2) < 1e-9
    pt.save_png(os.path.join(args.work, "diffraction_white_view.png"), white)
