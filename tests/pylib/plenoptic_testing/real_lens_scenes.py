# SPDX-License-Identifier: AGPL-3.0-or-later
"""The made-up vignetting lens that the real-lens render tests share, and their camera scene.

Import it as `from plenoptic_testing.real_lens_scenes import ...`.
"""
from . import lens_tracer as lt

# A triplet-like test lens of about 53 mm (made up for the test, not a published design): large
# front and rear elements, a small stop, so that the clear apertures vignette off axis.
LENS_ROWS = [
    (30.0, 6.0, 1.6, 24.0),
    (-200.0, 4.0, 1.0, 24.0),
    (0.0, 4.0, 0.0, 10.0),  # the stop
    (-40.0, 2.0, 1.6, 14.0),
    (60.0, 4.0, 1.0, 14.0),
    (100.0, 5.0, 1.6, 18.0),
    (-40.0, 0.0, 1.0, 18.0),
]
LENS_FILE_TEXT = "# test lens\n" + "".join("%r %r %r %r\n" % row for row in LENS_ROWS)


def inline_prescription():
    rows = []
    for radius, thickness, ior, aperture in LENS_ROWS:
        if radius == 0:
            rows.append("stop { thickness %r aperture %r }" % (thickness, aperture))
        else:
            rows.append("surface { radius %r thickness %r ior %r aperture %r }" % (radius, thickness, ior, aperture))
    return "prescription {\n      " + "\n      ".join(rows) + "\n    }"


def reference_lens():
    return lt.Lens(lt.parse_lens_file(LENS_FILE_TEXT))


def camera_scene(main_lens_block, rest, background="rgb 1", objects=""):
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { %s }\n"
            "camera { plenoptic location <0, 0, -3> look_at <0, 0, 0>\n"
            "  main_lens { %s }\n%s}\n%s" % (background, main_lens_block, rest, objects))
