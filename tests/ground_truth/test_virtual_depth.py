# SPDX-License-Identifier: AGPL-3.0-or-later
"""<image>.virtual_depth.exr of focused (2.0) cameras against the thin-lens equation.

Scenes: a Keplerian (d > f) and a Galilean (d < f) focused camera, F = 50 mm, look along +z at
two self-lit fronto-parallel planes, z = 0.5 m on the upper half and z = 1.5 m behind, with
nothing beyond the far plane's right part. For a plane at z the main lens images it at
b = F z / (z - F); the array is at D, the sensor d behind it, so v = -(D - b) / d (libpleno's
sign: positive behind the array). The EXR must hold that on every pixel whose depth map says it
sees the plane, (F - D) / d where the chief ray meets nothing, NaN where the pixel is blocked;
the metadata names the file; a plenoptic 1.0 camera writes none.
"""

import os

import numpy as np

import plenoptic_testing as pt

W, H = 320, 240
F, N_MAIN, FOCUS_M = 50.0, 2.8, 1.0
PITCH, MICRO_F, PIXEL = 0.15, 0.5, 0.01
Z_NEAR, Z_FAR = 0.5, 1.5

SCENE = """#declare Glow = finish { emission 1 diffuse 0 ambient 0 }
camera {
  plenoptic
  location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }
  microlens_array { hexagonal pitch %r focal_length %r distance %%r }
  sensor { pixel_size %r }
  samples 4
  depth_map
}
box { <-1, 0, %r>, <1, 1, %r> pigment { rgb <1, 0.6, 0.3> } finish { Glow } }
box { <-1, -1, %r>, <0.005, 1, %r> pigment { rgb <0.3, 0.6, 1> } finish { Glow } }
""" % (F, N_MAIN, FOCUS_M, PITCH, MICRO_F, PIXEL, Z_NEAR, Z_NEAR + 1e-4, Z_FAR, Z_FAR + 1e-4)


def thin_lens_v(z_mm, d):
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    b = F * z_mm / (z_mm - F)
    return -(D - b) / d


def test_virtual_depth_of_planes(args):
    checked = []
    for name, d in (("keplerian", 0.75), ("galilean", 0.3)):
        png, meta_path, depth_path = pt.render_ground_truth(args.povray, args.work, "vd_" + name, SCENE % d, W, H)
        meta = pt.read_json(meta_path)
        assert meta["virtual_depth_map"] == "vd_%s.virtual_depth.exr" % name, (
            "the metadata names the virtual depth map: %r" % meta["virtual_depth_map"])
        virtual = pt.load(os.path.join(args.work, meta["virtual_depth_map"]))[..., 0]
        depth = pt.load(depth_path)[..., 0]
        assert virtual.shape == (H, W)
        # The chief ray's distance tells which plane (or none) a pixel sees; its optics-frame
        # depth is not needed: every pixel of a plane has that plane's virtual depth.
        D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
        for z in (Z_NEAR, Z_FAR):
            # Distances along chief rays at most ~5 degrees off the axis: z <= r <= z / cos(5 deg).
            on = (depth >= z * 0.9999) & (depth <= z / np.cos(np.radians(5)) + 1e-3) & np.isfinite(depth)
            if z == Z_FAR:
                on &= depth > Z_NEAR / np.cos(np.radians(5)) + 1e-3
            expected = thin_lens_v(z * 1000.0, d)
            assert on.sum() > 0.1 * W * H, "%s: many pixels see the plane at %g (%d)" % (name, z, on.sum())
            worst = np.abs(virtual[on] - expected).max()
            assert worst < 1e-4 * max(1.0, abs(expected)), (
                "%s: virtual depth on the plane at %g m is the thin-lens %.5f (worst off by %.3g)"
                % (name, z, expected, worst))
            checked.append((name, z, expected, worst))
        sky = np.isinf(depth)
        assert sky.sum() > 0.02 * W * H, "%s: some chief rays meet nothing" % name
        assert np.allclose(virtual[sky], (F - D) / d, rtol=1e-5), (
            "%s: nothing hit: the point at infinity's virtual depth (F - D) / d = %.5f" % (name, (F - D) / d))
        blocked = depth < 0
        assert np.isnan(virtual[blocked]).all() and not np.isnan(virtual[~blocked]).any(), (
            "%s: NaN exactly where the depth map says blocked (-1)" % name)
        # Signs: the near plane images behind the array (v > 0), the far one in front (v < 0).
        assert thin_lens_v(Z_NEAR * 1000.0, d) > 0 > thin_lens_v(Z_FAR * 1000.0, d)
    print("virtual depth (camera, plane, thin-lens v, worst error): %s" % checked)

    png, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "vd_plenoptic1", SCENE % MICRO_F, W, H)
    meta = pt.read_json(meta_path)
    assert meta["virtual_depth_map"] is None and not os.path.exists(os.path.join(args.work, "vd_plenoptic1.virtual_depth.exr")), (
        "a plenoptic 1.0 camera (d = f) writes no virtual depth map")
