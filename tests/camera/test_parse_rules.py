# SPDX-License-Identifier: AGPL-3.0-or-later
"""Rules of the camera block that a hostile new user found broken.

1. A block given twice replaces the first entirely (docs/camera.md, Repeated keywords): a
   second `sensor { }` brings back the defaults of everything it does not set.
2. Parameters that leave the image black are not silent: `f_number 1e6`, or a focus distance
   within 1e-6 mm of the focal length, print a warning; the image is then indeed black
   (checked on the render), and a normal camera prints no such warning.
"""
import numpy as np
import pytest

import plenoptic_testing as pt

WORLD = """#version 3.7;
global_settings { assumed_gamma 1.0 }
light_source { <-3, 6, -4> rgb 1 }
sky_sphere { pigment { rgb 1 } }
plane { y, 0 pigment { checker rgb 0.2 rgb 0.9 scale 0.25 } }
"""
PLACE = "plenoptic location <0, 0.5, -2> look_at <0, 0.3, 0>"
ARRAY = "microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }"
DARK_WARNING = "almost no light reaches the sensor"


def camera(*parts):
    return WORLD + "camera {\n  " + "\n  ".join((PLACE,) + parts) + "\n}\n"


# 1. Repeated sensor blocks.
SENSOR_CASES = [
    ("sensor-repeated-empty", ["sensor { pixel_size 0.02 }", "sensor { }"], [0.01, 0.01], [0, 0]),
    ("sensor-repeated-partial", ["sensor { pixel_size 0.02 offset <0.1, 0> }", "sensor { pixel_size 0.03 }"],
     [0.03, 0.03], [0, 0]),
    ("sensor-once", ["sensor { pixel_size 0.02 offset <0.1, 0> }"], [0.02, 0.02], [0.1, 0]),
]

# 2. Black images warn; normal ones do not.
LENSES = [
    ("dark-f-number", "main_lens { thin_lens focal_length 16 f_number 1e6 focus_distance 2 }", True),
    ("dark-focus-at-focal-length",
     "main_lens { thin_lens focal_length 16 f_number 4 focus_distance 0.016 + 1e-9 }", True),
    ("normal", "main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }", False),
]


@pytest.mark.parametrize("name, blocks, pixel, offset", SENSOR_CASES, ids=[c[0] for c in SENSOR_CASES])
def test_repeated_sensor_block_replaces(args, name, blocks, pixel, offset):
    scene = camera("main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }", ARRAY,
                   *blocks, "samples 1")
    image = pt.render(args.povray, args.work, name, scene, 40, 30)
    sensor = pt.metadata_of(image)["sensor"]
    assert np.allclose(sensor["pixel_size_mm"], pixel) and np.allclose(sensor["offset_mm"], offset), (
        name + ": metadata pixel_size %s offset %s, expected %s %s"
        % (sensor["pixel_size_mm"], sensor["offset_mm"], pixel, offset))


@pytest.mark.parametrize("name, lens, dark", LENSES, ids=[c[0] for c in LENSES])
def test_black_image_warns(args, name, lens, dark):
    scene = camera(lens, ARRAY, "sensor { pixel_size 0.01 }", "samples 4")
    rc, text = pt.render(args.povray, args.work, name, scene, 60, 45, expect_failure=True)
    assert rc == 0, name + " renders: exit %d\n%s" % (rc, text[-2000:])
    warned = " ".join(text.split()).count(DARK_WARNING)  # POV-Ray wraps its messages
    mean = float(pt.load(pt.render(args.povray, args.work, name, scene, 60, 45))[:, :, :3].mean())
    if dark:
        assert warned == 1, name + " warns: warning printed %d time(s)" % warned
        assert mean < 1e-3, name + " is indeed dark: mean pixel value %.3g" % mean
    else:
        assert warned == 0 and mean > 0.05, (name + " is quiet and lit: warning printed %d time(s), mean %.3g"
                                             % (warned, mean))
