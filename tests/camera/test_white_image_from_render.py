# SPDX-License-Identifier: AGPL-3.0-or-later
"""White images kept by the render (docs/sensor.md "White images"): a whole render with a fixed
sample count keeps its white image at its own aperture from its own samples (each passing ray
brings 1 to a fifth channel beside r, g, b and t), instead of tracing the camera a second time.

The independent answer is the white image traced on its own, from the camera alone (the path every
other white image takes, itself checked against renders of a white world in test_white_image.py):
a render that leaves out its last row (+ER) cannot keep it, so it traces it; both must write the
same file, byte for byte (the same values and, through a read-out, the same noise frame), whatever
the scene, for each kind of camera whose sample loop differs (own lens, overlap, lit-area table,
aimed samples, spectral bands). Adaptive sampling stops by the scene's colours, so there the white
image is always traced on its own.
"""
import os

import pytest

import plenoptic_testing as pt
from plenoptic_testing.real_lens_scenes import inline_prescription

W, H = 96, 72
WORLD = ("background { rgb <0.2, 0.3, 0.9> }\nlight_source { <2, 3, -4> rgb 1 }\n"
         "sphere { <0, 0, 1>, 0.6 pigment { checker rgb 1 rgb <1, 0, 0> scale 0.1 } }")
THIN = "main_lens { thin_lens focal_length 16 f_number %s focus_distance 2 }"
ARRAY = "microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 }"
READ_OUT = "bayer rggb bit_depth 12 full_well 8000 exposure 4000 read_noise 2 black_level 64 seed 3"
KEPT = "from the render's own samples"

CAMERAS = {
    # The plain mean through the own lens (the vignetting probes at the microimages' rims).
    "thin": THIN % 4 + "\n  " + ARRAY + "\n  sensor { pixel_size 0.01 }\n  samples 16",
    # The same through a read-out: a raw white image, its own noise frame.
    "read_out": THIN % 4 + "\n  " + ARRAY + "\n  sensor { pixel_size 0.01 " + READ_OUT + " }\n  samples 16",
    # Microimages wider than their cells: the light of several lenses summed (overlap).
    "overlap": THIN % 2 + "\n  " + ARRAY + "\n  sensor { pixel_size 0.01 }\n  samples 16",
    # A traced prescription without an array: the lit-area table.
    "lit_area": "main_lens { %s focus_distance 3 }\n  sensor { pixel_size 0.05 }\n  samples 8" % inline_prescription(),
    # A traced prescription behind an array: samples aimed where light passes, with weights.
    "aimed": "main_lens { %s focus_distance 3 }\n  microlens_array { rectangular pitch 2.5 pinhole distance 8.5 }\n"
             "  sensor { pixel_size 0.5 }\n  samples 8" % inline_prescription(),
    # Spectral bands: the white channel weighted as red.
    "spectral": THIN % 4 + "\n  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 abbe 40 }\n"
                "  sensor { pixel_size 0.01 }\n  samples 8 spectral 4",
    # Adaptive sampling: never kept.
    "adaptive": THIN % 2.8 + "\n  " + ARRAY + "\n  sensor { pixel_size 0.01 }\n  samples 4, 32 confidence 0.9 variance 1/200",
}


def scene(camera):
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n%s\n"
            "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n  %s\n  white_image\n}\n" % (WORLD, camera))


def render(args, name, text, extra=()):
    """Renders `text` with no white image cache; returns (the white image's bytes, console text)."""
    saved = os.environ.pop("PLENOPTIC_WHITE_IMAGE_CACHE", None)
    try:
        pov = os.path.join(args.work, name + ".pov")
        pt.write_text(pov, text)
        out = os.path.join(args.work, name + ".png")
        pt.remove_outputs(args.work, name, "png")
        run = pt.run_povray(args.povray, pov, out, W, H, extra=list(pt.LINEAR16) + list(extra), timeout=300,
                            cwd=args.work)
        assert run.returncode == 0, run.output[-2000:]
    finally:
        if saved is not None:
            os.environ["PLENOPTIC_WHITE_IMAGE_CACHE"] = saved
    with open(os.path.join(args.work, name + ".white.png"), "rb") as f:
        return f.read(), run.output


@pytest.mark.parametrize("camera", sorted(CAMERAS))
def test_the_kept_white_image_is_the_one_traced_on_its_own(args, camera):
    text = scene(CAMERAS[camera])
    whole, log = render(args, "kept_" + camera, text)
    alone, alone_log = render(args, "alone_" + camera, text, extra=["+ER%d" % (H - 1)])
    assert KEPT not in alone_log, alone_log[-1500:]
    if camera == "adaptive":
        assert KEPT not in log, log[-1500:]
    else:
        assert KEPT in log, log[-1500:]
    assert whole == alone
