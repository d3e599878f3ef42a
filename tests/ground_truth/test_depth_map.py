# SPDX-License-Identifier: AGPL-3.0-or-later
"""The depth map (`depth_map` in camera { plenoptic }) against distances computed here.

Scene: a shifted plenoptic camera (thin main lens, hexagonal array at d = f, turned and shifted,
behind a shifted sensor) looks straight down +z at two fronto-parallel emissive planes: a near
one at z = 0.5 covering the upper part of the view, a far one at z = 2 covering x <= 0.08, and
nothing to the lower right (a white sky_sphere behind, which is not a surface).

For every pixel the test rebuilds the chief ray from the specification (docs/specification.md,
sections 2 and 3): the pixel centre, the lens
whose cell holds the pixel's projection from the main-lens centre onto the array, the line
through that lens's centre to the main lens (hit at m), refracted there by w' = w - m / F. Along
it, a plane at optics-frame depth z is at distance (z - m_z) / w_z (w unit length), converted
to scene units. The EXR must hold exactly that (float precision), +inf where the chief ray
meets nothing, and -1 exactly where no sample of the pixel passes the main aperture: pixels
whose chief ray crosses the main lens well inside the aperture are never -1, pixels whose
chief ray crosses it well outside always are, and -1 goes with a black pixel.
"""

import math

import numpy as np

import plenoptic_testing as pt

W, H = 320, 240
PIXEL = 0.01
F, N, FOCUS = 50.0, 4.0, 1.5
PITCH, MICRO_F = 0.15, 0.45
ROTATE_DEG = 4.0
TRANSLATE = np.array([0.02, -0.01])
OFFSET = np.array([0.012, -0.008])
LOCATION = np.array([0.05, -0.005, -1.0])
MM = 1000.0
Z_NEAR, Z_FAR, FAR_X_MAX = 0.5, 2.0, 0.08
EDGE_MM = 1.0  # pixels whose chief ray lands this close to a plane's edge are not compared

SCENE = """#declare Glow = finish { emission 1 diffuse 0 ambient 0 }
camera {
  plenoptic
  location <%r, %r, %r>
  look_at <%r, %r, %r>
  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }
  microlens_array { hexagonal pitch %r focal_length %r distance %r rotate <0, 0, %r> translate <%r, %r, 0> }
  sensor { pixel_size %r offset <%r, %r> }
  samples 16
  depth_map
}
sky_sphere { pigment { rgb 1 } }
box { <-1, 0, %r>, <1, 1, %r> pigment { gradient x color_map { [0 rgb 0.3] [1 rgb 1] } scale 0.01 } finish { Glow } }
box { <-5, -5, %r>, <%r, 5, %r>
  pigment { gradient y color_map { [0 rgb <1, 0.4, 0.3>] [1 rgb <0.3, 0.5, 1>] } scale 0.02 } finish { Glow } }
""" % (tuple(LOCATION) + tuple(LOCATION + [0, 0, 1]) + (F, N, FOCUS, PITCH, MICRO_F, MICRO_F, ROTATE_DEG)
       + tuple(TRANSLATE) + (PIXEL,) + tuple(OFFSET) + (Z_NEAR, Z_NEAR + 1e-3, Z_FAR, FAR_X_MAX, Z_FAR + 1e-3))


def expected_depth():
    """Distance (scene units) per pixel, +inf where nothing is hit, and a mask of pixels too close
    to an edge (a plane's, or a lens cell's) to compare; also |m| per pixel."""
    D = pt.image_distance(F, FOCUS * MM)
    d = MICRO_F
    A = F / N
    jj, ii = np.mgrid[0:H, 0:W]
    px, py = pt.sensor_point(ii, jj, W, H, PIXEL, PIXEL, *OFFSET)
    # Own lens: the line main-lens centre -> pixel meets the array plane z = -D at p D / (D + d).
    q = np.stack([px, py], axis=-1) * (D / (D + d))
    R = pt.rot_z(ROTATE_DEG)
    local = (q - TRANSLATE) @ R  # R^T (q - t), row vectors
    k, l, gap = pt.nearest_lens_local("hexagonal", PITCH, local)
    c = pt.lens_centre_local("hexagonal", PITCH, k, l) @ R.T + TRANSLATE
    # Chief ray: pixel -> lens centre (undeviated), on to the main lens, refracted there.
    w = (c - np.stack([px, py], axis=-1)) / d  # per unit z
    m = c + w * D
    w_out = w - m / F
    norm = np.sqrt((w_out ** 2).sum(axis=-1) + 1.0)
    depth = np.full((H, W), np.inf)
    unsure = gap < 1e-9 * PITCH * PITCH
    hit_done = np.zeros((H, W), bool)
    for z_world, inside in ((Z_NEAR, lambda x, y: (y >= 0) & (np.abs(x) <= 1)),
                            (Z_FAR, lambda x, y: (x <= FAR_X_MAX) & (np.abs(y) <= 5))):
        z = (z_world - LOCATION[2]) * MM  # optics-frame depth of the plane, mm
        hit = m + z * w_out
        x_world = LOCATION[0] + hit[..., 0] / MM
        y_world = LOCATION[1] + hit[..., 1] / MM
        before = hit_done.copy()  # already stopped by a nearer plane
        on = inside(x_world, y_world) & ~before
        depth = np.where(on, z * norm / MM, depth)
        # Near an edge the answer flips between surfaces: skip.
        edge = (np.abs(y_world) < EDGE_MM / MM) if z_world == Z_NEAR else (np.abs(x_world - FAR_X_MAX) < EDGE_MM / MM)
        unsure |= edge & ~before
        hit_done |= on
    return depth, unsure, np.hypot(m[..., 0], m[..., 1]), A, D, d


def test_depth_map(args):
    png, meta_path, depth_path = pt.render_ground_truth(args.povray, args.work, "depth_planes", SCENE, W, H)
    meta = pt.read_json(meta_path)
    assert meta["depth_map"] == "depth_planes.depth.exr", "metadata depth_map names the EXR beside the image: %r" % meta["depth_map"]

    import OpenImageIO as oiio
    from plenoptic_lf.images import ImageFile
    with ImageFile(depth_path) as depth:
        spec = depth.spec
        assert (spec.width == W and spec.height == H and tuple(spec.channelnames) == ("Z",)
                     and spec.format == oiio.TypeDesc("float")), ("depth EXR: %d x %d, channels %s, %s (want %d x %d, ('Z',), float)"
                     % (spec.width, spec.height, tuple(spec.channelnames), spec.format, W, H))
        measured = depth.read()[:, :, 0].astype(np.float64)
    image = pt.read_linear(png)

    expected, unsure, m_radius, A, D, d = expected_depth()
    blocked = measured == -1
    lit = ~blocked
    # A pixel's samples cross the main lens within (half a pixel diagonal) D / d + the cell's
    # circumradius of its chief ray's crossing m.
    spread = 0.5 * math.hypot(PIXEL, PIXEL) * D / d + PITCH / math.sqrt(3)
    surely_lit = m_radius < A / 2 - spread
    surely_blocked = m_radius > A / 2 + spread
    assert (surely_lit.sum() > 0.2 * W * H and surely_blocked.sum() > 100), ("geometry gives %d pixels that must receive light and %d that cannot"
                 % (surely_lit.sum(), surely_blocked.sum()))
    assert (not (blocked & surely_lit).any()), ("no pixel whose chief ray crosses the main lens %.2f mm inside "
                 "the aperture is -1 (found %d)" % (spread, (blocked & surely_lit).sum()))
    assert (not (lit & surely_blocked).any()), ("every pixel whose chief ray crosses the main lens %.2f mm "
                 "outside the aperture is -1 (%d are not)" % (spread, (lit & surely_blocked).sum()))
    black = (image == 0).all(axis=2)
    # -1 where the pixel is black. The camera aims its samples where light passes (docs/camera.md,
    # "Sampling"), so it also finds slivers of light too faint for the 16-bit image: such a pixel is
    # black without being -1, and lies at the rim of the lit field (never where light surely reaches).
    assert not (blocked & ~black).any(), "every -1 pixel is black (%d are not)" % (blocked & ~black).sum()
    faint = black & ~blocked
    assert (not (faint & surely_lit).any() and faint.sum() <= 0.01 * W * H), (
        "a black pixel that is not -1 receives light too faint for the image, at the rim of the lit field "
        "(%d such pixels, %d of them where light surely reaches)" % (faint.sum(), (faint & surely_lit).sum()))
    others = np.isfinite(measured) & ~blocked
    assert not (measured[others] < 0).any(), "no other negative depths (%d)" % (measured[others] < 0).sum()

    compare = lit & ~unsure
    finite = compare & np.isfinite(expected)
    infinite = compare & ~np.isfinite(expected)
    assert (finite.sum() > 0.3 * W * H and infinite.sum() > 0.05 * W * H), "%d pixels compared with a plane distance, %d that see nothing" % (finite.sum(), infinite.sum())
    relative = np.abs(measured[finite] - expected[finite]) / expected[finite]
    worst = int(np.argmax(relative))
    where = np.argwhere(finite)[worst]
    assert (relative.max() <= 2e-6), ("depth = (z - m_z) / w_z along the chief ray: worst relative error %.2g "
                 "at pixel (%d, %d): %.9g vs %.9g (float32 storage: <= 2e-6)"
                 % (relative.max(), where[1], where[0], measured[tuple(where)], expected[tuple(where)]))
    near = finite & (expected < 0.6 * (Z_FAR - LOCATION[2]))
    assert (near.sum() > 0.1 * W * H and (finite & ~near).sum() > 0.1 * W * H), "both planes are compared (%d near, %d far pixels)" % (near.sum(), (finite & ~near).sum())
    wrong_inf = infinite & ~np.isposinf(measured)
    assert (not wrong_inf.any()), ("+inf where the chief ray meets no surface (%d of %d pixels are not)"
                 % (wrong_inf.sum(), infinite.sum()))
    stray_inf = finite & np.isinf(measured)
    assert not stray_inf.any(), "no +inf where a plane is hit (%d)" % stray_inf.sum()

