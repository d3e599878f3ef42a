# SPDX-License-Identifier: AGPL-3.0-or-later
"""White images (docs/sensor.md "White images"): `white_image` writes what the camera
records of a uniform white diffuser, computed from the camera alone (no scene ray).

The independent answer is the render itself: the same camera rendering a world whose every
direction is white (background rgb 1, no object) must give the same picture, pixel for pixel, as
its white image: same samples, same vignetting, same overlap. Checked for a thin main lens with
a hexagonal thin-lens array, for a traced prescription with cat's-eye microimages, and for each
f-number of `f_numbers` against a render at that f-number. With a sensor read-out the white image
is a raw in DN (its own noise), and `noise_free` gives the linear one.
"""
import os

import numpy as np
import pytest

import plenoptic_testing as pt
from plenoptic_testing.real_lens_scenes import inline_prescription

W, H = 120, 90
THIN = "main_lens { thin_lens focal_length 16 f_number %s focus_distance 2 }"
ARRAY = "microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 } sensor { pixel_size 0.01 %s }"


def scene(main, array_sensor, extra):
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 1 }\n"
            "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n  %s\n  %s\n  samples 16 %s\n}\n"
            % (main, array_sensor, extra))


def white_values(path):
    return pt.load(path)[..., 0]


def white_linear(path):
    """A linear white image's values (pt.white_image_values) and scale, the scale checked: the
    smallest power of two at or above the largest value."""
    values, scale = pt.white_image_values(path)
    values = values[..., 0]
    assert values.max() <= scale + 1e-9 and (scale == 1 or values.max() > scale / 2), (values.max(), scale)
    return values, scale


def assert_equal_to_render(white, scale, rendered, what):
    """The white image against a 16-bit render of a white world, to both quantisations; where the
    render clipped at 1 (light of neighbouring lenses adding up), the white image holds more."""
    step = pt.white_image_step(scale)
    unclipped = white <= 1 - step
    diff = np.abs(white - rendered)[unclipped]
    print("%s: white image - render of a white world: max %.2g over %d of %d pixels below 1 (scale %g)"
          % (what, diff.max() if diff.size else 0, unclipped.sum(), white.size, scale))
    assert diff.size == 0 or diff.max() <= step, diff.max()
    assert (rendered[~unclipped] >= 1 - step).all()


@pytest.mark.parametrize("case", ["thin", "prescription"])
def test_white_image_equals_a_render_of_a_white_world(args, case):
    if case == "thin":
        main, array_sensor = THIN % 4, ARRAY % ""
    else:
        main = "main_lens { %s focus_distance 3 }" % inline_prescription()
        array_sensor = "microlens_array { rectangular pitch 2.5 pinhole distance 8.5 } sensor { pixel_size 0.5 }"
    path = pt.render(args.povray, args.work, "white_" + case, scene(main, array_sensor, "white_image"), W, H)
    rendered = pt.read_linear(path)[..., 0]
    white_path = os.path.splitext(path)[0] + ".white.png"
    white, scale = white_linear(white_path)
    assert white.shape == rendered.shape
    assert 0.05 < rendered.mean() < 0.95, rendered.mean()  # microimages, not a flat field
    assert_equal_to_render(white, scale, rendered, case)
    meta = pt.metadata_of(path)
    assert meta["white_images"] == [{"file": os.path.basename(white_path), "f_number": meta["main_lens"]["f_number"],
                                     "values": "linear", "scale": scale}]
    pt.save_png(os.path.join(args.work, "white_%s_view.png" % case), white)


def test_white_images_at_f_numbers(args):
    path = pt.render(args.povray, args.work, "white_fnumbers",
                     scene(THIN % 4, ARRAY % "", "white_image f_numbers <2.8, 5.6>"), W, H)
    stem = os.path.splitext(path)[0]
    meta = pt.metadata_of(path)
    assert [w["file"] for w in meta["white_images"]] == ["white_fnumbers.white.f2.8.png", "white_fnumbers.white.f5.6.png"]
    assert [w["f_number"] for w in meta["white_images"]] == [2.8, 5.6]
    assert not os.path.exists(stem + ".white.png")
    means = []
    for n in (2.8, 5.6):
        at = pt.render(args.povray, args.work, "white_at_%g" % n, scene(THIN % n, ARRAY % "", ""), W, H)
        white, scale = white_linear("%s.white.f%g.png" % (stem, n))
        assert_equal_to_render(white, scale, pt.read_linear(at)[..., 0], "f/%g" % n)
        # Unclipped: against the same render as half floats (11 significant bits), where the
        # light of neighbouring lenses adds up to more than a lit cell's.
        exr = pt.load(pt.render(args.povray, args.work, "white_at_%g_exr" % n, scene(THIN % n, ARRAY % "", ""), W, H,
                                ext="exr"))[..., 0]
        assert np.abs(white - exr).max() <= 1e-3 * max(1.0, exr.max()) + scale / 65535.0, (n, np.abs(white - exr).max())
        means.append(white.mean())
    # A smaller aperture, smaller microimages: less light (area ratio (2.8 / 5.6)^2 within the cells).
    assert means[1] < 0.6 * means[0], means


def test_white_image_through_the_read_out(args):
    body = "bayer rggb bit_depth 12 full_well 8000 exposure 4000 read_noise 2 black_level 64 seed 3"
    path = pt.render(args.povray, args.work, "white_raw", scene(THIN % 4, ARRAY % body, "white_image"), W, H)
    stem = os.path.splitext(path)[0]
    dn = np.rint(white_values(stem + ".white.png") * 65535)
    rendered = pt.read_linear(path)[..., 0]
    # DN = 64 + e (4095 - 64) / 8000, e = 4000 x value with shot and read noise (far from the full
    # well, so nothing clips): the mean follows.
    expected = 64 + rendered * 4000 * (4095 - 64) / 8000.0
    assert abs(dn.mean() - expected.mean()) < 2.0, (dn.mean(), expected.mean())
    assert np.abs(dn - expected).max() > 3  # noisy, unlike the picture
    assert pt.metadata_of(path)["white_images"][0]["values"] == "dn"
    # noise_free: the linear white image, though the camera has a read-out.
    path = pt.render(args.povray, args.work, "white_clean", scene(THIN % 4, ARRAY % body, "white_image noise_free"), W, H)
    white, scale = white_linear(os.path.splitext(path)[0] + ".white.png")
    assert_equal_to_render(white, scale, pt.read_linear(path)[..., 0], "noise_free")
    assert pt.metadata_of(path)["white_images"][0]["values"] == "linear"
    # Without white_image, none.
    path = pt.render(args.povray, args.work, "white_none", scene(THIN % 4, ARRAY % "", ""), W, H)
    assert pt.metadata_of(path)["white_images"] is None
    assert not os.path.exists(os.path.splitext(path)[0] + ".white.png")
