# SPDX-License-Identifier: AGPL-3.0-or-later
"""The metadata's distortion profile of a traced prescription against the independent
reference tracer of the tests (plenoptic_testing.lens_tracer).

For each row the reference places the object point on the plane that its own paraxial trace
images onto the array (Newton's equation from its focal points), finds the chief ray through the
centre of the stop by the secant method on the reference's trace of the surfaces in front of the
stop, traces it through the whole lens (no clear apertures: every surface opened to its
hemisphere) and intersects it with the image plane. Heights must agree within 1e-6 mm, field
angles within 1e-6 degrees. Lenses: the tests' made-up triplet (stop inside) and the 22 mm
inverted telephoto of lenses/ (strong barrel distortion).
"""
import math
import os

import numpy as np
import pytest

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt
from plenoptic_testing.real_lens_scenes import LENS_FILE_TEXT, camera_scene

LENSES_DIR = os.path.join(os.path.dirname(__file__), "..", "..", "lenses")
WIDE_ANGLE = "wide_angle_22mm_laikin_f3.5.dat"


def opened(lens):
    """The same lens with every surface open to its hemisphere (the stop: 1 m wide)."""
    rows = [s._replace(aperture=1e3 if s.is_stop else 2.0 * abs(s.radius)) for s in lens.surfaces]
    return lt.Lens(rows)


def reference_chief_height(lens, object_point, image_z):
    """Lens frame: the chief ray from object_point (z < 0) through the stop's centre; its height
    (y) on the plane z = image_z, and its field angle (degrees)."""
    par = lt.paraxial_data(lens)
    full = opened(lens)
    front = lt.Lens(list(full.surfaces[:lens.stop_index])) if lens.stop_index > 0 else None
    stop_z = lens.vertex_z[lens.stop_index]
    origin = np.array(object_point, float)

    def stop_height(t):
        direction = np.array([0.0, t, par.entrance_pupil_z]) - origin
        if front is None:
            point, d = origin, direction / np.linalg.norm(direction)
        else:
            traced = lt.trace_object_to_image(front, origin, direction)
            assert traced.passed
            point, d = traced.points, traced.directions
        return point[1] + (stop_z - point[2]) / d[2] * d[1]

    t0, t1 = 0.0, 1e-3
    y0, y1 = stop_height(t0), stop_height(t1)
    for _ in range(50):
        if abs(y1) < 1e-13 or y1 == y0:
            break
        t0, t1, y0 = t1, t1 - y1 * (t1 - t0) / (y1 - y0), y1
        y1 = stop_height(t1)
    assert abs(y1) < 1e-9
    direction = np.array([0.0, t1, par.entrance_pupil_z]) - origin
    traced = lt.trace_object_to_image(full, origin, direction)
    assert traced.passed
    p, d = traced.points, traced.directions
    height = p[1] + (image_z - p[2]) / d[2] * d[1]
    u = direction / np.linalg.norm(direction)
    return height, math.degrees(math.atan2(math.hypot(u[0], u[1]), abs(u[2])))


@pytest.mark.parametrize("which", ["triplet", "wide_angle"])
def test_profile_matches_reference(args, which):
    if which == "triplet":
        text, W, H, pixel = LENS_FILE_TEXT, 48, 36, 0.5
    else:
        with open(os.path.join(LENSES_DIR, WIDE_ANGLE)) as f:
            text = f.read()
        W, H, pixel = 48, 32, 0.6
    pt.write_text(os.path.join(args.work, "profile_lens.dat"), text)
    scene = camera_scene('lens_file "profile_lens.dat" focus_distance 3',
                         "  sensor { pixel_size <%r, %r> } samples 1\n" % (pixel, pixel))
    path = pt.render(args.povray, args.work, "profile_" + which, scene, W, H, extra=("+L%s" % args.work,))
    meta = pt.metadata_of(path)
    profile = meta["main_lens"]["distortion_profile"]
    assert profile["chief_ray"].startswith("through the centre of the aperture stop")
    D = meta["main_lens"]["distance_mm"]
    lens = lt.Lens(lt.parse_lens_file(text))
    par = lt.paraxial_data(lens)
    L = lens.length
    # Newton: x x' = f^2 from the reference's focal points (lens frame, +z towards the image).
    x_image = (L + D) - par.rear_focal_z
    object_z = par.front_focal_z - par.efl ** 2 / x_image
    assert profile["image_plane_z_mm"] == pytest.approx(-D, abs=1e-12)
    assert profile["object_plane_z_mm"] == pytest.approx(L - object_z, rel=1e-9)
    magnification = x_image / par.efl
    corner = math.hypot(W * pixel / 2, H * pixel / 2)
    rows = profile["samples"]
    assert len(rows) == 17, len(rows)
    worst_height = worst_angle = 0.0
    distortion = []
    for relative, angle, paraxial, real, percent in rows:
        assert paraxial == pytest.approx(relative * corner, rel=1e-12, abs=1e-12)
        height, ref_angle = reference_chief_height(lens, (0.0, paraxial / magnification, object_z), L + D)
        # The object is above the axis, its image below: the profile reports heights positive on
        # the paraxial image's side.
        worst_height = max(worst_height, abs(real - (-height)))
        worst_angle = max(worst_angle, abs(angle - ref_angle))
        if paraxial > 0:
            assert percent == pytest.approx(100 * (real / paraxial - 1), rel=1e-9, abs=1e-12)
            distortion.append(percent)
    print("%s: heights within %.2e mm, angles within %.2e deg; distortion at the corner %.3f %%"
          % (which, worst_height, worst_angle, distortion[-1]))
    assert worst_height <= 1e-6 and worst_angle <= 1e-6
    if which == "wide_angle":
        assert distortion[-1] < -1.0  # an inverted telephoto: barrel
