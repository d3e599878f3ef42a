# SPDX-License-Identifier: AGPL-3.0-or-later
"""Unit tests of the reference lens tracer (tests/pylib/plenoptic_testing/lens_tracer.py) that
the prescription main-lens tests compare the camera with. Each answer here comes
from a closed form of textbook optics, never from the tracer itself: the axis crossing of a
ray refracted by one sphere, the thick-lens focal length and principal planes, Gaussian
imaging for pupils and image distances, Snell's law and the critical angle at a flat face,
and the geometry of pinhole microimages behind a bare stop. Renders nothing; no povray needed.
"""
import math

import numpy as np
import pytest

from plenoptic_testing import lens_tracer as lt

# An invented triplet (f about 44 mm, f/3.1), not a published design: a lens of several
# glasses with an inner stop, for the tests that need no closed form of their own.
TRIPLET = """
# radius  thickness  ior   aperture
  21.0    4.0        1.62  17       # positive crown
 -160.0   4.5        1     17
 -28.0    1.2        1.60  12       # negative flint
  22.0    2.0        1     12
  0       2.5        0     11       # aperture stop (index 0: medium unchanged)
  70.0    3.5        1.62  15
 -24.0    40         1     15       # last thickness: pbrt's film distance, not used
"""


def axis_crossing(lens, height, start_z=-10.0):
    """z where a ray parallel to the axis at the given height (in x) crosses the axis (the line
    of the traced ray beyond the last surface, extended either way)."""
    result = lt.trace_object_to_image(lens, [[height, 0.0, start_z]], [[0.0, 0.0, 1.0]])
    assert result.passed[0], "the ray at height %g was blocked" % height
    point, direction = result.points[0], result.directions[0]
    return point[2] - point[0] * direction[2] / direction[0]


def single_surface_axis_crossing(radius, n1, n2, height):
    """Closed form: a ray parallel to the axis at `height` meets a sphere of (signed) radius R,
    vertex at z = 0, going from index n1 into n2. Incidence i: sin i = h / R (the normal is the
    line to the centre C at z = R); refraction n1 sin i = n2 sin i'. In the triangle
    (C, hit point P, crossing F) the angle at P is i', at C it is pi - i, so at F it is i - i',
    and the law of sines gives CF = R sin i' / sin(i - i'): F is at z = R + CF (signed)."""
    incidence = math.asin(height / radius)
    refraction = math.asin(n1 * math.sin(incidence) / n2)
    return radius + radius * math.sin(refraction) / math.sin(incidence - refraction)


def thick_lens(n, r1, r2, thickness):
    """Textbook thick lens in air (Hecht, Optics, 6.2): focal length from the lensmaker's
    equation with its thickness term, and the principal planes' offsets from the vertices
    (positive towards the image): h1 = -f (n - 1) t / (n R2), h2 = -f (n - 1) t / (n R1)."""
    f = 1.0 / ((n - 1.0) * (1.0 / r1 - 1.0 / r2 + (n - 1.0) * thickness / (n * r1 * r2)))
    return f, -f * (n - 1.0) * thickness / (n * r2), -f * (n - 1.0) * thickness / (n * r1)


def gauss_image(f, object_distance):
    """Image distance behind the rear principal plane, 1/s + 1/s' = 1/f (negative: virtual)."""
    return object_distance * f / (object_distance - f)


# ------------------------------------------------------------------------------------------
# The prescription

def test_parse_lens_file_reads_rows_comments_and_the_stop():
    surfaces = lt.parse_lens_file(TRIPLET)
    assert len(surfaces) == 7
    assert surfaces[0] == lt.Surface(21.0, 4.0, 1.62, 17.0, False)
    assert surfaces[4] == lt.Surface(0.0, 2.5, 0.0, 11.0, True)
    lens = lt.Lens(surfaces)
    assert lens.stop_index == 4
    assert lens.length == pytest.approx(17.7, abs=1e-12)  # the last row's thickness is not counted
    assert list(lens.vertex_z) == pytest.approx([0.0, 4.0, 8.5, 9.7, 11.7, 14.2, 17.7], abs=1e-12)
    assert list(lens.medium_after) == [1.62, 1.0, 1.60, 1.0, 1.0, 1.62, 1.0]
    # The same lens as dicts, the stop by its flag without radius or index.
    rows = [{"radius": s.radius, "thickness": s.thickness, "ior": s.ior, "aperture": s.aperture}
            for s in surfaces]
    rows[4] = {"stop": True, "thickness": 2.5, "aperture": 11.0}
    assert lt.Lens(rows).surfaces == lens.surfaces


@pytest.mark.parametrize("text, message", [
    ("50 5 1.5\n", "expected 4 numbers"),
    ("50 5 1.5 abc\n", "not a number"),
    ("# nothing\n", "no surface"),
    ("50 5 1.5 20\n0 1 1 10\n-50 0 1 20\n", "stop cannot change the index"),
    ("5 1 1.5 20\n", "cannot hold a clear aperture"),
    ("50 1 0 20\n", "not positive"),
    ("0 1 0 10\n0 1 0 10\n", "more than one aperture stop"),
])
def test_malformed_prescriptions_are_refused(text, message):
    with pytest.raises(ValueError, match=message):
        lt.Lens(lt.parse_lens_file(text))


# ------------------------------------------------------------------------------------------
# Exact tracing against closed forms

@pytest.mark.parametrize("radius, n1, n2", [
    (20.0, 1.0, 1.5),     # convex air -> glass: converges
    (-20.0, 1.0, 1.5),    # concave air -> glass: diverges (virtual crossing in front)
    (-20.0, 1.6, 1.0),    # convex glass -> air (entered through a flat face): converges
    (25.0, 1.7, 1.2),     # concave glass -> lighter glass
])
def test_one_spherical_surface_crosses_the_axis_where_the_closed_form_says(radius, n1, n2):
    rows = [] if n1 == 1.0 else [{"radius": math.inf, "thickness": 10.0, "ior": n1, "aperture": 30.0}]
    vertex = 0.0 if n1 == 1.0 else 10.0
    lens = lt.Lens(rows + [{"radius": radius, "thickness": 0.0, "ior": n2, "aperture": 30.0}])
    paraxial_focus = n2 * radius / (n2 - n1)
    for height in (0.5, 2.0, 5.0, 8.0, 12.0):
        expected = vertex + single_surface_axis_crossing(radius, n1, n2, height)
        assert axis_crossing(lens, height) == pytest.approx(expected, abs=1e-9), height
    # Spherical aberration is there (the test is not paraxial), and vanishes towards the axis
    # where the closed form tends to the paraxial focus, which the y-u trace gives too.
    assert abs(single_surface_axis_crossing(radius, n1, n2, 12.0) - paraxial_focus) > 0.1
    assert single_surface_axis_crossing(radius, n1, n2, 1e-4) == pytest.approx(paraxial_focus, rel=1e-7)
    assert lt.paraxial_data(lens).rear_focal_z == pytest.approx(vertex + paraxial_focus, rel=1e-12)


@pytest.mark.parametrize("direction_deg, azimuth_deg", [(0, 0), (10, 0), (25, 40), (60, 200), (85, -70)])
def test_snell_at_a_flat_surface(direction_deg, azimuth_deg):
    lens = lt.Lens([{"radius": math.inf, "thickness": 0.0, "ior": 1.5, "aperture": 400.0}])
    theta, phi = math.radians(direction_deg), math.radians(azimuth_deg)
    incoming = [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)]
    start = np.array([1.0, -2.0, -3.0])
    result = lt.trace_object_to_image(lens, [start], [incoming])
    theta_out = math.asin(math.sin(theta) / 1.5)
    expected = [math.sin(theta_out) * math.cos(phi), math.sin(theta_out) * math.sin(phi), math.cos(theta_out)]
    assert result.passed[0]
    assert result.directions[0] == pytest.approx(expected, abs=1e-14)
    hit = start + np.array(incoming) * 3.0 / math.cos(theta)
    assert result.points[0] == pytest.approx(hit, abs=1e-12)


def test_total_internal_reflection_beyond_the_critical_angle():
    # A ray through the centre of curvature of the first surface enters it undeviated (normal
    # incidence) and meets the flat back face at its own angle from the normal: transmitted
    # with sin(out) = n sin(in) below the critical angle asin(1/n), blocked beyond it.
    n = 1.5
    lens = lt.Lens([{"radius": 10.0, "thickness": 11.0, "ior": n, "aperture": 19.9},
                    {"radius": math.inf, "thickness": 0.0, "ior": 1.0, "aperture": 60.0}])
    critical = math.degrees(math.asin(1.0 / n))
    centre = np.array([0.0, 0.0, 10.0])
    angles = [0.0, 20.0, 40.0, critical - 0.01, critical + 0.01, 45.0, 55.0]
    directions = np.array([[math.sin(math.radians(a)), 0.0, math.cos(math.radians(a))] for a in angles])
    result = lt.trace_object_to_image(lens, centre - 12.0 * directions, directions)
    for angle, passed, direction in zip(angles, result.passed, result.directions):
        assert passed == (angle < critical), angle
        if passed:
            out = math.asin(n * math.sin(math.radians(angle)))
            assert direction == pytest.approx([math.sin(out), 0.0, math.cos(out)], abs=1e-12), angle
    # From the image side a ray in air always gets into the glass, even at grazing incidence
    # (89 degrees, aimed at the axis point of the flat face).
    grazing = np.array([-math.sin(math.radians(89.0)), 0.0, -math.cos(math.radians(89.0))])
    back = lt.trace_image_to_object(lens, [[0.0, 0.0, 11.0] - 0.5 * grazing], [grazing])
    assert back.passed[0]


def test_clear_apertures_and_the_stop_block_outside_their_radius():
    # A flat plate (apertures 10 and 8) with a 6 mm stop between its faces; rays parallel to
    # the axis keep their height through it.
    lens = lt.Lens([{"radius": math.inf, "thickness": 2.0, "ior": 1.5, "aperture": 10.0},
                    {"stop": True, "thickness": 2.0, "aperture": 6.0},
                    {"radius": math.inf, "thickness": 0.0, "ior": 1.0, "aperture": 8.0}])
    assert list(lens.medium_after) == [1.5, 1.5, 1.0]
    heights = np.array([0.0, 2.9999, 3.0001, 4.5, 5.5])
    origins = np.stack([heights, np.zeros(5), np.full(5, -1.0)], axis=1)
    forward = lt.trace_object_to_image(lens, origins, [0.0, 0.0, 1.0])
    assert list(forward.passed) == [True, True, False, False, False]
    stopped_down = lt.Lens(lens.surfaces, stop_diameter=4.0)
    assert list(lt.trace_object_to_image(stopped_down, origins, [0.0, 0.0, 1.0]).passed) == [True, False, False, False, False]
    # A ray that misses a sphere entirely is blocked.
    ball = lt.Lens([{"radius": 5.0, "thickness": 0.0, "ior": 1.5, "aperture": 10.0}])
    assert not lt.trace_object_to_image(ball, [[6.0, 0.0, -1.0]], [[0.0, 0.0, 1.0]]).passed[0]


def polygon_contains(corners, x, y):
    """Points inside or on a convex polygon whose corners are listed counter-clockwise."""
    inside = np.ones(np.shape(x), dtype=bool)
    for (x0, y0), (x1, y1) in zip(corners, np.roll(corners, -1, axis=0)):
        inside &= (x1 - x0) * (y - y0) - (y1 - y0) * (x - x0) >= -1e-12
    return inside


def iris_corners(blades, rotation_deg, radius):
    """The documented iris: corners on the stop circle at rotation + (2k + 1) 180/N degrees."""
    angles = np.radians(rotation_deg + (2 * np.arange(blades) + 1) * 180.0 / blades)
    return np.stack([radius * np.cos(angles), radius * np.sin(angles)], axis=1)


@pytest.mark.parametrize("blades, rotation", [(6, 0.0), (5, 10.0), (3, -35.0)])
def test_iris_is_the_documented_polygon(blades, rotation):
    lens = lt.Lens([{"stop": True, "thickness": 0.0, "aperture": 10.0}], iris_blades=blades,
                   iris_rotation_deg=rotation)
    rng = np.random.default_rng(blades)
    x, y = rng.uniform(-5.5, 5.5, (2, 20000))
    passed = lt.trace_object_to_image(lens, np.stack([x, y, np.full_like(x, -1.0)], axis=1), [0, 0, 1]).passed
    assert np.array_equal(passed, polygon_contains(iris_corners(blades, rotation, 5.0), x, y))
    if rotation == 0.0:  # hexagon: a flat side faces +x at 5 cos 30 deg, a corner at 30 deg
        apothem = 5.0 * math.cos(math.radians(30))
        corner = np.radians(30.0)
        x = np.array([apothem - 1e-6, apothem + 1e-6, 4.999 * math.cos(corner)])
        y = np.array([0.0, 0.0, 4.999 * math.sin(corner)])
        probe = lt.trace_object_to_image(lens, np.stack([x, y, -np.ones(3)], axis=1), [0, 0, 1]).passed
        assert list(probe) == [True, False, True]


def test_rays_retrace_their_way_back():
    lens = lt.Lens(lt.parse_lens_file(TRIPLET))
    rng = np.random.default_rng(7)
    count = 20000
    origins = np.stack([rng.uniform(-30, 30, count), rng.uniform(-30, 30, count), np.full(count, -200.0)], axis=1)
    targets = np.stack([rng.uniform(-9, 9, count), rng.uniform(-9, 9, count), np.zeros(count)], axis=1)
    forward = lt.trace_object_to_image(lens, origins, targets - origins)
    assert 1000 < forward.passed.sum() < count
    passed = forward.passed
    back = lt.trace_image_to_object(lens, forward.points[passed] + 5.0 * forward.directions[passed],
                                    -forward.directions[passed])
    assert back.passed.all()
    # The returned ray points back at where it came from.
    start = origins[passed]
    to_start = start - back.points
    along = np.einsum("ij,ij->i", to_start, back.directions)
    miss = np.linalg.norm(to_start - along[:, None] * back.directions, axis=1)
    assert miss.max() < 1e-8
    initial = (targets - origins)[passed]
    assert np.abs(back.directions + initial / np.linalg.norm(initial, axis=1)[:, None]).max() < 1e-12


# ------------------------------------------------------------------------------------------
# Paraxial data against the thick-lens formulas

R1, R2, THICKNESS, GLASS = 50.0, -80.0, 6.0, 1.6


def biconvex(stop_row=None, stop_gap=0.0):
    """The thick biconvex lens, with a stop row `stop_gap` in front ("front") or behind ("rear")."""
    first = {"radius": R1, "thickness": THICKNESS, "ior": GLASS, "aperture": 30.0}
    second = {"radius": R2, "thickness": stop_gap if stop_row == "rear" else 0.0, "ior": 1.0, "aperture": 30.0}
    stop = {"stop": True, "thickness": stop_gap if stop_row == "front" else 0.0, "aperture": 8.0}
    return lt.Lens({None: [first, second], "front": [stop, first, second], "rear": [first, second, stop]}[stop_row])


@pytest.mark.parametrize("n, r1, r2, thickness", [(1.6, 50.0, -80.0, 6.0), (1.5, 100.0, -100.0, 0.5),
                                                   (1.8, 30.0, 200.0, 8.0), (1.5, -40.0, -25.0, 5.0)])
def test_thick_lens_focal_length_and_principal_planes(n, r1, r2, thickness):
    lens = lt.Lens([{"radius": r1, "thickness": thickness, "ior": n, "aperture": 20.0},
                    {"radius": r2, "thickness": 0.0, "ior": 1.0, "aperture": 20.0}])
    f, h1, h2 = thick_lens(n, r1, r2, thickness)
    data = lt.paraxial_data(lens)
    assert data.efl == pytest.approx(f, rel=1e-12)
    assert data.front_principal_z == pytest.approx(h1, abs=1e-9)
    assert data.rear_principal_z == pytest.approx(thickness + h2, abs=1e-9)
    assert data.bfd == pytest.approx(f + h2, abs=1e-9)
    assert data.ffd == pytest.approx(f - h1, abs=1e-9)
    assert data.rear_focal_z == pytest.approx(thickness + h2 + f, abs=1e-9)
    assert data.front_focal_z == pytest.approx(h1 - f, abs=1e-9)
    # No stop row: the stop is the surface an axial beam from infinity fills first. Both
    # openings are 20 mm; the marginal ray of height 1 reaches the second surface at height
    # 1 - t (n - 1) / (n R1) (slope after one refraction), so the second surface limits when
    # the beam widens, and the entrance pupil is then 20 mm divided by that height.
    second_height = 1.0 - thickness * (n - 1.0) / (n * r1)
    pupil = 20.0 if second_height <= 1.0 else 20.0 / second_height
    assert data.stop_index == (0 if second_height <= 1.0 else 1)
    assert data.entrance_pupil_diameter == pytest.approx(pupil, rel=1e-12)
    assert data.f_number == pytest.approx(f / pupil, rel=1e-12)


def test_exact_trace_near_the_axis_meets_the_paraxial_focus():
    for lens in (biconvex(), lt.Lens(lt.parse_lens_file(TRIPLET))):
        focus = lt.paraxial_data(lens).rear_focal_z
        assert axis_crossing(lens, 1e-3) == pytest.approx(focus, abs=1e-6)


@pytest.mark.parametrize("object_distance", [60.0, 100.0, 500.0, 3000.0, 30.0, math.inf])
def test_paraxial_image_distance_follows_gauss(object_distance):
    f, h1, h2 = thick_lens(GLASS, R1, R2, THICKNESS)
    got = lt.paraxial_image_distance(biconvex(), object_distance)
    if math.isinf(object_distance):
        assert got == pytest.approx(f + h2, abs=1e-9)
    else:
        assert got == pytest.approx(h2 + gauss_image(f, object_distance + h1), rel=1e-12)


@pytest.mark.parametrize("gap", [5.0, 20.0, 80.0])
def test_pupils_are_the_gaussian_images_of_the_stop(gap):
    f, h1, h2 = thick_lens(GLASS, R1, R2, THICKNESS)
    # Stop in front: it is the entrance pupil; the exit pupil is its image through the lens,
    # the stop lying gap + h1 in front of the front principal plane.
    data = lt.paraxial_data(biconvex("front", gap))
    assert data.stop_index == 0
    assert (data.entrance_pupil_z, data.entrance_pupil_diameter) == (0.0, 8.0)
    image = gauss_image(f, gap + h1)
    assert data.exit_pupil_z == pytest.approx(gap + THICKNESS + h2 + image, rel=1e-12)
    assert data.exit_pupil_diameter == pytest.approx(8.0 * abs(image / (gap + h1)), rel=1e-12)
    assert data.f_number == pytest.approx(f / 8.0, rel=1e-12)
    # Stop behind: it is the exit pupil; the entrance pupil is its image seen from the front,
    # the stop lying gap - h2 behind the rear principal plane.
    data = lt.paraxial_data(biconvex("rear", gap))
    assert data.stop_index == 2
    assert data.exit_pupil_z == pytest.approx(THICKNESS + gap, abs=1e-12)
    assert data.exit_pupil_diameter == pytest.approx(8.0, rel=1e-12)
    image = gauss_image(f, gap - h2)
    assert data.entrance_pupil_z == pytest.approx(h1 - image, rel=1e-12)
    diameter = 8.0 * abs(image / (gap - h2))
    assert data.entrance_pupil_diameter == pytest.approx(diameter, rel=1e-12)
    assert data.f_number == pytest.approx(f / diameter, rel=1e-12)


# ------------------------------------------------------------------------------------------
# The camera around the lens

def test_world_to_optics_puts_the_front_vertex_at_z_L():
    lens = lt.Lens(lt.parse_lens_file(TRIPLET))
    got = lt.world_to_optics([[1.1, 2.2, 3.3], [1.0, 2.0, 3.0]], location=[1.0, 2.0, 3.0],
                             right=[0, 0, 2.0], up=[0, 3.0, 0], direction=[-0.5, 0, 0], mm_per_unit=1000.0, lens=lens)
    assert got == pytest.approx(np.array([[300.0, 200.0, -100.0 + 17.7], [0.0, 0.0, 17.7]]), abs=1e-9)
    assert lt.optics_lens_mirror([[1.0, 2.0, 17.7], [0.0, 0.0, 0.0]], lens) == pytest.approx(
        np.array([[1.0, 2.0, 0.0], [0.0, 0.0, 17.7]]), abs=1e-12)


@pytest.mark.parametrize("height", [0.0, 5.0, 20.0])
def test_spot_centroid_is_the_paraxial_image_for_a_small_stop(height):
    # f/26 with the stop in front, object 1 m in front, sensor in the paraxial image plane:
    # the centroid is the Gaussian image (magnification -s'/s from the principal planes) up
    # to third-order distortion and coma, below 0.2 um at these heights (0.02 rad).
    f, h1, h2 = thick_lens(GLASS, R1, R2, THICKNESS)
    lens = biconvex("front", 5.0)
    lens = lt.Lens(lens.surfaces, stop_diameter=2.0)
    object_distance = 1000.0
    s = object_distance + 5.0 + h1
    image = gauss_image(f, s)
    D = 5.0 + THICKNESS + h2 + image - lens.length
    spot = lt.spot_centroid_no_array(lens, [height, 0.0, lens.length + object_distance], D, 20000)
    assert spot.count > 15000
    assert spot.x == pytest.approx(-image / s * height, abs=2e-4)
    assert spot.y == pytest.approx(0.0, abs=1e-12)
    u, v = lt.sensor_to_pixel(spot.x, spot.y, 100, 80, 0.01, 0.01)
    assert (u, v) == pytest.approx((49.5 + image / s * height / 0.01, 39.5), abs=0.03)


def bare_stop_white_image(blades, rotation, D, d, pitch, W, H, pixel, n):
    """The closed form for a stop alone (no glass) at z = 0 of diameter A: the ray from sensor
    point S through pinhole centre C crosses z = 0 at X = (C (D + d) - S D) / d, so lens k is
    seen from S exactly when X lies in the opening: the microimage is the opening scaled by
    -d/D about C (D + d)/D. Evaluated at the same stratified points as the tracer's."""
    fractions = (np.arange(n) + 0.5) / n
    x = -((np.arange(W)[:, None] + fractions) - W / 2.0) * pixel
    y = ((np.arange(H)[:, None] + fractions) - H / 2.0) * pixel
    sy, sx = np.meshgrid(y.ravel(), x.ravel(), indexing="ij")
    counts = np.zeros_like(sx)
    reach = 6.0 * d / D / pitch + 2
    for k in range(int(-W * pixel / pitch - reach), int(W * pixel / pitch + reach)):
        for l in range(int(-H * pixel / pitch - reach), int(H * pixel / pitch + reach)):
            cx = (k * pitch * (D + d) - sx * D) / d
            cy = (l * pitch * (D + d) - sy * D) / d
            if blades:
                counts += polygon_contains(iris_corners(blades, rotation, 6.0), cx, cy)
            else:
                counts += cx * cx + cy * cy <= 36.0
    return counts.reshape(H, n, W, n).mean(axis=(1, 3))


@pytest.mark.parametrize("blades, rotation", [(0, 0.0), (5, 10.0)])
def test_white_image_of_a_bare_stop_is_the_closed_form(blades, rotation):
    # Microimages of radius 6 * 1 / 20 = 0.3 mm = 3 pitches: up to a dozen lenses overlap at
    # each point, so this also checks that white_image_pinhole_array misses no lens.
    lens = lt.Lens([{"stop": True, "thickness": 0.0, "aperture": 12.0}], iris_blades=blades,
                   iris_rotation_deg=rotation)
    D, d, pitch, W, H, pixel, n = 20.0, 1.0, 0.1, 48, 40, 0.01, 4
    got = lt.white_image_pinhole_array(lens, D, d, pitch, W, H, pixel, pixel, n)
    expected = bare_stop_white_image(blades, rotation, D, d, pitch, W, H, pixel, n)
    assert got.shape == (H, W)
    assert expected.mean() > 5.0
    # Points exactly on a microimage border may round either way.
    assert np.abs(got - expected).max() <= 1.0 / n ** 2 + 1e-12
    assert (got != expected).mean() < 0.01


def test_white_image_of_a_lens_of_revolution_is_symmetric():
    lens = lt.Lens(lt.parse_lens_file(TRIPLET))
    D = lt.paraxial_data(lens).bfd
    image = lt.white_image_pinhole_array(lens, D, 0.5, 0.15, 40, 40, 0.01, 0.01, 4)
    assert image.max() > 1.0 and image.min() >= 0.0 and image[20, 20] == 1.0
    for mirrored in (image[:, ::-1], image[::-1, :], image.T):
        assert np.abs(image - mirrored).max() <= 1.0 / 16 + 1e-12
        assert (image != mirrored).mean() < 0.02
