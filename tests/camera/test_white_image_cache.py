# SPDX-License-Identifier: AGPL-3.0-or-later
"""The white images' cache (docs/sensor.md "White images", "Cached white images"): with
PLENOPTIC_WHITE_IMAGE_CACHE naming a folder, a white image is computed once per camera and
reused by any scene through the same camera.

The independent answer is the white image computed without a cache: a cached one must be the same
file, byte for byte (the same values, the same noise frame through a read-out), whatever scene
the camera looks at. Any change of an optical parameter must make a new entry, and a damaged
entry must never be used.
"""
import glob
import os
import shutil

import pytest

import plenoptic_testing as pt

W, H = 96, 72
CAMERA = ("main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }\n"
          "  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance %s }\n"
          "  sensor { pixel_size 0.01 %s }\n  samples 4 %s")
READ_OUT = "bayer rggb bit_depth 12 full_well 8000 exposure 4000 read_noise 2 black_level 64 seed 3"


def scene(world, distance="0.4", sensor="", white="white_image"):
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n%s\n"
            "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n  %s\n}\n"
            % (world, CAMERA % (distance, sensor, white)))


SKY = "background { rgb <0.2, 0.3, 0.9> }"
SPHERES = ("background { rgb 0 }\nlight_source { <2, 3, -4> rgb 1 }\n"
           "sphere { <0, 0, 1>, 0.6 pigment { checker rgb 1 rgb <1, 0, 0> scale 0.1 } }")


def render(args, name, text, cache):
    """Renders with the cache folder `cache` (None: no cache); returns (white image bytes by
    suffix, console text)."""
    saved = os.environ.get("PLENOPTIC_WHITE_IMAGE_CACHE")
    try:
        if cache is None:
            os.environ.pop("PLENOPTIC_WHITE_IMAGE_CACHE", None)
        else:
            os.environ["PLENOPTIC_WHITE_IMAGE_CACHE"] = cache
        pov = os.path.join(args.work, name + ".pov")
        pt.write_text(pov, text)
        out = os.path.join(args.work, name + ".png")
        pt.remove_outputs(args.work, name, "png")
        run = pt.run_povray(args.povray, pov, out, W, H, extra=pt.LINEAR16, timeout=120, cwd=args.work)
        assert run.returncode == 0, run.output[-2000:]
    finally:
        if saved is None:
            os.environ.pop("PLENOPTIC_WHITE_IMAGE_CACHE", None)
        else:
            os.environ["PLENOPTIC_WHITE_IMAGE_CACHE"] = saved
    whites = {}
    for path in glob.glob(os.path.join(args.work, name + ".white*.png")):
        with open(path, "rb") as f:
            whites[path[len(os.path.join(args.work, name)):]] = f.read()
    assert whites, "no white image written"
    return whites, run.output


def entries(cache):
    return sorted(os.path.basename(p) for p in glob.glob(os.path.join(cache, "*.png")))


@pytest.mark.parametrize("sensor", ["", READ_OUT], ids=["linear", "read_out"])
def test_a_cached_white_image_is_the_computed_one_for_any_scene(args, sensor):
    cache = os.path.join(args.work, "cache_" + ("raw" if sensor else "linear"))
    shutil.rmtree(cache, ignore_errors=True)
    fresh, _ = render(args, "fresh", scene(SKY, sensor=sensor), None)
    first, log = render(args, "first", scene(SKY, sensor=sensor), cache)
    assert "computed, and cached" in log and "the cached one" not in log, log[-1500:]
    assert "from the render's own samples" in log, log[-1500:]  # kept by the render, then stored
    assert first == fresh  # storing changes nothing
    assert len(entries(cache)) == 1, entries(cache)
    # Another scene through the same camera: the white image comes from the cache, and is the one
    # a render without the cache computes.
    second, log = render(args, "second", scene(SPHERES, sensor=sensor), cache)
    assert "the cached one" in log and "computed, and cached" not in log, log[-1500:]
    assert "from the render's own samples" not in log, log[-1500:]  # the cache held it: not kept
    assert second == fresh
    assert len(entries(cache)) == 1


def test_every_f_number_is_an_entry_and_a_changed_camera_a_new_one(args):
    cache = os.path.join(args.work, "cache_keys")
    shutil.rmtree(cache, ignore_errors=True)
    white = "white_image f_numbers <2.8, 5.6>"
    fresh, _ = render(args, "fnumbers_fresh", scene(SKY, white=white), None)
    render(args, "fnumbers_first", scene(SKY, white=white), cache)
    assert len(entries(cache)) == 2
    again, log = render(args, "fnumbers_again", scene(SPHERES, white=white), cache)
    assert log.count("the cached one") == 2, log[-1500:]
    assert again == fresh
    # One optical parameter changed (the array 1 um further from the sensor): new entries, and the
    # white images of that camera, not the cached ones.
    moved_fresh, _ = render(args, "moved_fresh", scene(SKY, distance="0.401", white=white), None)
    moved, log = render(args, "moved", scene(SPHERES, distance="0.401", white=white), cache)
    assert "the cached one" not in log and log.count("computed, and cached") == 2, log[-1500:]
    assert moved == moved_fresh and moved != fresh
    assert len(entries(cache)) == 4


def test_a_damaged_entry_is_never_used(args):
    cache = os.path.join(args.work, "cache_damaged")
    shutil.rmtree(cache, ignore_errors=True)
    fresh, _ = render(args, "damaged_first", scene(SKY), cache)
    (entry,) = glob.glob(os.path.join(cache, "*.png"))
    with open(entry, "r+b") as f:  # cut short, as a full disk or a killed copy would leave it
        f.truncate(os.path.getsize(entry) // 2)
    again, log = render(args, "damaged_again", scene(SPHERES), cache)
    assert "the cached one" not in log and "computed, and cached" in log, log[-1500:]
    assert again == fresh
    # The record names another camera's description: not used either.
    (record,) = glob.glob(os.path.join(cache, "*.json"))
    with open(record) as f:
        text = f.read()
    with open(record, "w") as f:
        f.write(text.replace("f_number 4", "f_number 4.5", 1))
    third, log = render(args, "damaged_third", scene(SPHERES), cache)
    assert "the cached one" not in log, log[-1500:]
    assert third == fresh
