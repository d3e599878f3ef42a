# SPDX-License-Identifier: AGPL-3.0-or-later
"""Spectral sampling (docs/spectral.md), rendered.

- A grey world through a lens that does not disperse renders with `spectral 8` as without it, in
  expectation: per channel, the mean difference of the two images is within 4 standard errors of
  zero (the errors from the pixels' differences themselves), for a plenoptic camera behind a
  traced singlet.
- A white world through a dispersing singlet (V_d 20) stays neutral on the axis: without an array
  the central pixels have R = G = B; with an array, so have the centres of the microimages near the
  axis, where every band's light passes whole, while the rims of the microimages carry colour (the
  exit pupil's image differs with the wavelength), so the test could tell dispersion from none.
- Longitudinal colour: a point source imaged by the dispersing singlet without an array, the sensor
  at the d line's focus, spreads blue wider than red or green by an amount of the sign the
  thin-lens formula f / V_d gives (blue focuses nearer: defocused at the sensor).
- The same render with 1 and 2 threads is the same, byte for byte.
- A response table that is broken is refused with its file and line.
"""
import os

import numpy as np

import plenoptic_testing as pt

HEADER = pt.WORLD_HEADER


def scene(background, main, array="", extra=""):
    return (HEADER + "background { rgb %s }\n" % background +
            "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n  %s\n  %s\n  %s\n}\n" % (main, array, extra))


def main_lens(abbe, placement="focus_distance 2"):
    glass = " abbe %g" % abbe if abbe else ""
    return ("main_lens { prescription { stop { thickness 2 aperture 8 }"
            " surface { radius 30 thickness 5 ior 1.5168 aperture 20%s }"
            " surface { radius -30 thickness 0 ior 1 aperture 20 } } %s }" % (glass, placement))


ARRAY = "microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }"


def render(args, name, text, width, height, extra=()):
    work = os.path.join(args.work, "spectral")
    return pt.render(args.povray, work, name, text, width, height, extra=extra)


def test_grey_world_equals_render_without_spectral_in_expectation(args):
    plain = pt.read_linear(render(args, "grey_plain", scene(0.5, main_lens(0), ARRAY, "samples 16"), 120, 90))
    spectral = pt.read_linear(render(args, "grey_spectral", scene(0.5, main_lens(0), ARRAY, "samples 16 spectral 8"),
                                     120, 90))
    difference = spectral - plain
    for c in range(3):
        d = difference[:, :, c].ravel()
        standard_error = d.std() / np.sqrt(d.size)
        assert standard_error > 0, "the two renders differ pixel by pixel (their samples do)"
        assert abs(d.mean()) < 4 * standard_error, (c, d.mean(), standard_error)
    # The mean level itself: both are the same light.
    assert abs(spectral.mean() - plain.mean()) < 0.002 * plain.mean()


def test_white_world_through_a_dispersing_lens_is_neutral_on_the_axis(args):
    # No array: the sensor at the d line's focus of an object 2 m away.
    image = pt.read_linear(render(args, "white_noarray", scene(1, main_lens(20), "", "samples 16 spectral 8"), 41, 31))
    centre = image[13:18, 18:23]
    assert np.abs(centre[:, :, 0] - centre[:, :, 1]).max() < 2e-4, centre
    assert np.abs(centre[:, :, 2] - centre[:, :, 1]).max() < 2e-4, centre
    assert centre.min() > 0.5

    # With an array: the microimages' centres near the axis are neutral, their rims are not.
    path = render(args, "white_array", scene(1, main_lens(20), ARRAY, "samples 16 spectral 8"), 120, 90)
    image = pt.read_linear(path)
    meta = pt.load_metadata(os.path.splitext(path)[0] + ".plenoptic.json")
    assert "spectral" in meta and meta["spectral"]["bands"] == 8
    grey = image.mean(axis=2)
    neutral = np.abs(image - grey[:, :, None]).max(axis=2)
    # Pixels inside a microimage: they and their neighbours lit in every channel (at least 0.99).
    from scipy.ndimage import minimum_filter
    lit = minimum_filter(image.min(axis=2), size=3) > 0.99
    rim = (grey > 0.05) & (grey < 0.7)
    assert lit.sum() > 100 and rim.sum() > 100
    # Fully lit pixels near the axis: every band's samples all pass.
    h, w = grey.shape
    near = np.zeros_like(lit)
    near[h // 2 - 15:h // 2 + 15, w // 2 - 15:w // 2 + 15] = True
    assert neutral[lit & near].max() < 2e-4, neutral[lit & near].max()
    # The rims are coloured: blue's exit pupil, and so its microimages, differ from red's. Each
    # band takes 2 of the pixel's 16 samples, so a rim pixel's colour is noisy either way; the
    # glass shows as a systematic B - R over the rim pixels, many standard errors from zero, where
    # the same camera through a lens that does not disperse shows none.
    def rim_colour(picture):
        level = picture.mean(axis=2)
        rim = (level > 0.05) & (level < 0.7)
        d = (picture[:, :, 2] - picture[:, :, 0])[rim]
        assert d.size > 100
        return d.mean(), d.std() / np.sqrt(d.size)
    mean, error = rim_colour(image)
    assert abs(mean) > 4 * error, (mean, error)
    plain = pt.read_linear(render(args, "white_array_plain", scene(1, main_lens(0), ARRAY, "samples 16 spectral 8"),
                                  120, 90))
    mean_plain, error_plain = rim_colour(plain)
    assert abs(mean_plain) < 4 * error_plain, (mean_plain, error_plain)


def second_moment(channel):
    """The mean squared distance of the light from its centroid (px^2)."""
    total = channel.sum()
    ys, xs = np.indices(channel.shape)
    cy, cx = (channel * ys).sum() / total, (channel * xs).sum() / total
    return (channel * ((ys - cy) ** 2 + (xs - cx) ** 2)).sum() / total


def test_longitudinal_colour_blurs_blue_at_the_d_focus(args):
    # A small bright sphere on the axis, 2 m away, the sensor at the d line's focus: red, green
    # and blue each come to a focus elsewhere by about f / V_d (f 29.6 mm, V_d 20: 1.5 mm), blue
    # in front (the singlet refracts it more), so blue spreads widest; red's weights straddle the
    # d line less than blue's do, so red is sharper than blue.
    text = (HEADER + "background { rgb 0 }\n"
            "sphere { <0, 0, 0>, 0.004 pigment { rgb 1 } finish { ambient 1 diffuse 0 } }\n"
            "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n  %s\n"
            "  sensor { pixel_size 0.005 }\n  samples 64 spectral 8\n}\n" % main_lens(20))
    image = pt.read_linear(render(args, "point", text, 81, 81))
    spread = [second_moment(image[:, :, c]) for c in range(3)]
    assert spread[2] > 1.5 * spread[1], spread
    assert spread[2] > spread[0], spread

    plain = (HEADER + "background { rgb 0 }\n"
             "sphere { <0, 0, 0>, 0.004 pigment { rgb 1 } finish { ambient 1 diffuse 0 } }\n"
             "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n  %s\n"
             "  sensor { pixel_size 0.005 }\n  samples 64 spectral 8\n}\n" % main_lens(0))
    image = pt.read_linear(render(args, "point_plain", plain, 81, 81))
    spread_plain = [second_moment(image[:, :, c]) for c in range(3)]
    assert max(spread_plain) < 1.2 * min(spread_plain), spread_plain


def test_spectral_render_is_the_same_on_any_number_of_threads(args):
    text = scene(0.5, main_lens(20), ARRAY, "samples 6 spectral 4") + \
        "plane { z, 1 pigment { checker rgb <1, 0.2, 0.1> rgb <0.1, 0.3, 1> scale 0.05 } finish { ambient 1 diffuse 0 } }\n"
    one = render(args, "threads1", text, 64, 48, extra=("+WT1",))
    a = pt.read_pixels(one, native=True).copy()
    two = render(args, "threads2", text, 64, 48, extra=("+WT2",))
    b = pt.read_pixels(two, native=True)
    assert np.array_equal(a, b)


def test_broken_response_table_is_refused_with_file_and_line(args):
    work = os.path.join(args.work, "spectral")
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "sensor.csv"), "w") as f:
        f.write("wavelength_nm, r, g, b\n380, 0, 0, 1\n550, 0, 1\n720, 1, 0, 0\n")
    status, output = pt.render(args.povray, work, "badtable",
                               scene(0.5, main_lens(0), ARRAY, 'samples 4 spectral 8 response_file "sensor.csv"'),
                               16, 12, expect_failure=True)
    assert status != 0
    output = " ".join(output.split())  # POV-Ray wraps its messages
    assert 'response_file "sensor.csv", line 3' in output and "4 numbers" in output, output[-1500:]
    assert not os.path.exists(os.path.join(work, "badtable.png"))

    with open(os.path.join(work, "good.csv"), "w") as f:
        f.write("380, 0, 0, 1\n550, 0, 1, 0\n720, 1, 0, 0\n")
    status, output = pt.render(args.povray, work, "both",
                               scene(0.5, main_lens(0), ARRAY,
                                     'samples 4 spectral 8 response_centres <600, 540, 460> response_file "good.csv"'),
                               16, 12, expect_failure=True)
    output = " ".join(output.split())
    assert status != 0 and "response_file or response_centres" in output, output[-1500:]
    # The good table renders.
    pt.render(args.povray, work, "table", scene(0.5, main_lens(0), ARRAY, 'samples 4 spectral 8 response_file "good.csv"'),
              16, 12)
