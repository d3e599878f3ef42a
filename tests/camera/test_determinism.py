# SPDX-License-Identifier: AGPL-3.0-or-later
"""Determinism: the same scene and options give the same image, whatever the threads.

docs/specification.md, section 3. A textured scene through the most involved set-up the camera has
(thin main lens, multi-focus hexagonal array, rotated and translated, overlapping
microimages, adaptive sampling, a depth map) is rendered with one thread, with two
threads, and with two threads and tiny render blocks (a different order of pixels
across threads). The three images, depth maps, microimage-centre files and metadata files must be
identical (apart from the files' own names in the metadata).
"""
import os

import numpy as np

import plenoptic_testing as pt

W, H = 160, 120
CAMERA = """
camera { plenoptic location <0.15, 0.7, -3> look_at <0, 0.45, 0>
  main_lens { thin_lens focal_length 12 f_number 2.8 focus_distance 2.5 }
  microlens_array { hexagonal pitch 0.1 focal_lengths <0.3, 0.33, 0.36> distance 0.3
                    rotate <0.4, -0.3, 3> translate <0.01, -0.02, 0.005> }
  sensor { pixel_size 0.008 }
  samples 4, 32 confidence 0.95 variance 1/256
  depth_map
  microimage_centres
}
"""


def test_determinism_across_thread_counts(args):
    runs = [("wt1", ["+WT1"]), ("wt2", ["+WT2"]), ("wt2_bs4", ["+WT2", "+BS4"])]
    images, depths, metas, centres = {}, {}, {}, {}
    for name, extra in runs:
        path = pt.render(args.povray, args.work, name, pt.TEXTURED_SCENE + CAMERA, W, H, extra=extra)
        images[name] = pt.load(path)
        meta = pt.metadata_of(path)
        depth_file = meta.get("depth_map")
        depths[name] = pt.load(os.path.join(args.work, depth_file)) if depth_file else None
        meta.pop("depth_map", None)
        virtual_file = meta.pop("virtual_depth_map", None)
        if virtual_file:
            depths[name + " virtual depth"] = pt.load(os.path.join(args.work, virtual_file))
        with open(os.path.join(args.work, meta["microimages"].pop("file")), "rb") as f:
            centres[name] = f.read()
        metas[name] = meta
    ref = "wt1"
    assert depths[ref] is not None, "depth map written" + ": " + ("metadata depth_map: %r" % (depths[ref] is not None))
    for name, _ in runs[1:]:
        diff = np.abs(images[name] - images[ref]).max(axis=2)
        assert (int((diff > 0).sum()) == 0), ("image %s == %s" % (name, ref) + ": " + ("%d of %d pixels differ, max |diff| %.3g (expected 0)"
                     % (int((diff > 0).sum()), W * H, float(diff.max()))))
        if depths[ref] is not None and depths[name] is not None:
            a, b = depths[ref], depths[name]
            same = np.array_equal(a, b) or np.array_equal(np.nan_to_num(a, posinf=-9), np.nan_to_num(b, posinf=-9))
            assert same, "depth map %s == %s" % (name, ref) + ": " + ("%d values differ" % int((np.nan_to_num(a, posinf=-9) != np.nan_to_num(b, posinf=-9)).sum()))
        key = " virtual depth"
        assert (ref + key in depths) == (name + key in depths), "a virtual depth map in every run or in none"
        if ref + key in depths:
            assert np.array_equal(np.nan_to_num(depths[ref + key], nan=-9), np.nan_to_num(depths[name + key], nan=-9)), (
                "virtual depth map %s == %s" % (name, ref))
        assert metas[name] == metas[ref], "metadata %s == %s" % (name, ref) + ": " + ("identical apart from the names of the depth map and the microimage centres: %s" % (metas[name] == metas[ref]))
        assert centres[name] == centres[ref], "microimage centres %s == %s: byte for byte" % (name, ref)
    # The image must hold a real picture, or identity would prove little.
    spread = float(images[ref][:, :, :3].std())
    assert spread > 0.05, "the render is not trivial" + ": " + ("standard deviation of the pixels %.3f" % spread)

