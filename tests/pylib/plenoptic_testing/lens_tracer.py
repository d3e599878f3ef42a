# SPDX-License-Identifier: AGPL-3.0-or-later
"""Reference optics of a main lens given by a prescription, written for the tests
independently of the camera's code: exact sequential ray tracing through spherical surfaces,
paraxial data by a y-u paraxial ray trace, and the camera's geometry around the lens.

Import it as `from plenoptic_testing import lens_tracer`.

Prescription (pbrt's RealisticCamera lens file). One surface a row, object side first, four
numbers in mm: curvature radius, thickness, index of refraction, clear aperture diameter; an
optional fifth, the Abbe number V_d of the medium after the surface (0 or absent: it does not
disperse).
  - radius: signed; positive when the centre of curvature lies on the image side of the
    vertex. 0 marks the aperture stop (a flat opening). `inf` (dict form: math.inf) is a flat
    refracting surface.
  - thickness: axial distance from this surface's vertex to the next one's. The last row's
    thickness is not part of the lens (pbrt keeps the film distance there); the camera's D
    replaces it.
  - index: of the medium after the surface. The medium before the first surface is air
    (index 1). On the stop row the index is 0 or equal to the medium before the stop: the
    stop is an opening and never changes the medium (0 means "unchanged"; in every real
    lens that medium is air). Any other value on a stop row is refused.
  - aperture: clear diameter. A ray whose hit point lies farther than aperture/2 from the axis
    is blocked. A spherical surface needs aperture/2 <= |radius|.
  - V_d (optional): the index is then n_d, and at a wavelength lambda (nm) the standard two-term
    model n(lambda) = n_d + (n_d - 1) / V_d * (523655 / lambda^2 - 1.5168) gives it
    (`two_term_index`; `surfaces_at_wavelength` turns a prescription into the one at lambda).
`#` starts a comment. A lens may have at most one stop row; without one, the pupils and the
f-number are those of the surface that limits an axial beam from infinity.

Lens frame: z = 0 at the front vertex (first surface), +z towards the image, x and y as in the
camera's optics frame, millimetres. Surface i's vertex is at the sum of the thicknesses before
it; L (`Lens.length`) is the rear vertex's z.

Iris (optional, `Lens(..., iris_blades=N, iris_rotation_deg=rot)`): the opening of the stop is
the regular N-gon inscribed in the stop circle (its corners on the circle of the stop's
diameter), with corners at the angles rot + (2 k + 1) * 180/N degrees from +x towards +y,
k = 0 .. N-1. So a flat side's midpoint is at angle rot + k * 360/N, at distance
(diameter/2) cos(180/N) from the axis: with rot = 0 one flat side faces +x. A point passes
when it lies inside or on the polygon (and inside the circle, which the polygon is in).

Exact tracing: a ray meets a spherical surface at the first point (smallest parameter t >=
-1e-9 mm along its unit direction) of the half of the sphere that holds the vertex; no such
point (a miss) blocks the ray, as does a hit outside the clear aperture, a stop hit outside
the stop's opening, or total internal reflection. Refraction is Snell's law in vector form
with the surface normal at the hit point. Rays are numpy arrays (..., 3).

Camera geometry (the conventions of the prescription main lens):
  - Optics frame: +z towards the scene, millimetres. The rear vertex is at z = 0 and the front
    vertex at z = +L, so a lens-frame point (x, y, z) is the optics-frame point (x, y, L - z)
    and back (`optics_lens_mirror`; directions: (x, y, -z)).
  - The scene's `location` is the front vertex; a world point P is the optics-frame point
    ((P - location).right_u, (P - location).up_u, (P - location).dir_u) * mm_per_unit
    + (0, 0, L), right_u, up_u and dir_u being the unit vectors of right, up and direction
    (`world_to_optics`).
  - The array plane is z = -D (D: rear vertex -> array, mm) and the sensor z = -(D + d);
    without an array the sensor is at z = -D.
  - Pixels: W x H, size sx, sy, no offset: pixel (i, j)'s centre is on the sensor at
    x = -((i + 0.5) - W/2) sx, y = ((j + 0.5) - H/2) sy, and pixel (i, j) covers
    [i, i + 1) x [j, j + 1) in those (i, j) terms. Continuous pixel coordinates (u, v) put
    pixel (i, j)'s centre at (i, j) (`sensor_to_pixel(x, y, W, H, sx, sy)`: the package's
    own, re-exported here).
  - Rectangular microlens array of pitch p: lens (k, l) is centred at (k p, l p, -D); a
    pinhole microlens passes only the ray through its centre.
"""
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from . import sensor_to_pixel  # noqa: F401  (re-exported: the package's pixel convention)

# An intersection this far behind a ray's origin (mm) still counts: a ray that starts on a
# surface, or meets two surfaces at the same vertex, is not lost to rounding.
T_MIN = -1e-9

# Largest number of candidate (sensor point, microlens) pairs handled at once by
# white_image_pinhole_array (bounds its memory to a few hundred MB).
CANDIDATES_PER_BLOCK = 2_000_000


# ============================================================================================
# Prescriptions

class Surface(NamedTuple):
    """One row of a prescription (mm). radius: signed, math.inf for flat, ignored on the stop;
    ior: of the medium after the surface (0 on the stop: unchanged); aperture: diameter."""
    radius: float
    thickness: float
    ior: float
    aperture: float
    is_stop: bool
    abbe: float = 0.0


def parse_lens_file(text):
    """The surfaces of a lens file's text (module docstring: format), object side first.
    Raises ValueError naming the line of a malformed row."""
    surfaces = []
    for number, line in enumerate(text.splitlines(), 1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        if len(fields) not in (4, 5):
            raise ValueError("line %d: expected 4 numbers (radius thickness ior aperture), or 5 with V_d, got %d"
                             % (number, len(fields)))
        try:
            values = [float(f) for f in fields] + [0.0] * (5 - len(fields))
        except ValueError:
            raise ValueError("line %d: not a number in %r" % (number, line.strip()))
        radius, thickness, ior, aperture, abbe = values
        surfaces.append(Surface(radius, thickness, ior, aperture, radius == 0.0, abbe))
    if not surfaces:
        raise ValueError("the lens file has no surface")
    return surfaces


def two_term_index(n_d, abbe, wavelength_nm):
    """The two-term dispersion model (module docstring): the index at wavelength_nm of a glass
    of d-line index n_d and Abbe number abbe (n_d itself for abbe 0)."""
    if not abbe:
        return n_d
    return n_d + (n_d - 1.0) / abbe * (523655.0 / wavelength_nm ** 2 - 1.5168)


def surfaces_at_wavelength(surfaces, wavelength_nm):
    """The prescription at a wavelength: every medium with an Abbe number at its two-term index
    there, everything else (radii, thicknesses, apertures, the stop) unchanged."""
    return [s._replace(ior=two_term_index(s.ior, s.abbe, wavelength_nm)) if s.abbe and not s.is_stop else s
            for s in surfaces]


def surface_from_dict(row):
    """A Surface from a dict with keys radius, thickness, ior, aperture and optionally stop
    (default: radius == 0). A stop may omit radius (0) and ior (0: medium unchanged)."""
    is_stop = bool(row.get("stop", row.get("radius", 0.0) == 0.0))
    return Surface(float(row.get("radius", 0.0)), float(row["thickness"]),
                   float(row.get("ior", 0.0) if is_stop else row["ior"]), float(row["aperture"]), is_stop)


class Lens:
    """A prescription ready to trace.

    surfaces: Surface rows (parse_lens_file) or dicts (surface_from_dict), object side first.
    stop_diameter: replaces the stop row's diameter (stopping down); needs a stop row.
    iris_blades, iris_rotation_deg: the polygonal iris at the stop (module docstring); 0 blades
    is a round stop.

    Attributes: surfaces; curvature (1/radius, 0 for flat surfaces and the stop); vertex_z
    (lens frame); length (L, the rear vertex's z); medium_before and medium_after (indices
    around each surface); stop_index (None without a stop row); stop_diameter (None without
    one); iris_blades, iris_rotation_deg.
    """

    def __init__(self, surfaces, stop_diameter=None, iris_blades=0, iris_rotation_deg=0.0):
        self.surfaces = tuple(s if isinstance(s, Surface) else surface_from_dict(s) for s in surfaces)
        if not self.surfaces:
            raise ValueError("a lens needs at least one surface")
        stops = [i for i, s in enumerate(self.surfaces) if s.is_stop]
        if len(stops) > 1:
            raise ValueError("more than one aperture stop (rows %s)" % stops)
        self.stop_index = stops[0] if stops else None
        medium = 1.0
        before, after = [], []
        for i, s in enumerate(self.surfaces):
            if not (s.aperture > 0 and math.isfinite(s.aperture)):
                raise ValueError("surface %d: clear aperture %r is not a positive diameter" % (i, s.aperture))
            if not (s.thickness >= 0 and math.isfinite(s.thickness)):
                raise ValueError("surface %d: thickness %r is not a length >= 0" % (i, s.thickness))
            if s.is_stop:
                if s.ior not in (0.0, medium):
                    raise ValueError("surface %d: the stop cannot change the index (%g after %g)"
                                     % (i, s.ior, medium))
            else:
                if not (s.ior > 0 and math.isfinite(s.ior)):
                    raise ValueError("surface %d: index %r is not positive" % (i, s.ior))
                if s.radius == 0.0 or abs(s.radius) < s.aperture / 2.0:
                    raise ValueError("surface %d: radius %g cannot hold a clear aperture of %g"
                                     % (i, s.radius, s.aperture))
            before.append(medium)
            medium = medium if s.is_stop else s.ior
            after.append(medium)
        self.medium_before = np.array(before)
        self.medium_after = np.array(after)
        self.curvature = np.array([0.0 if s.is_stop else 1.0 / s.radius for s in self.surfaces])
        self.vertex_z = np.concatenate([[0.0], np.cumsum([s.thickness for s in self.surfaces[:-1]])])
        self.length = float(self.vertex_z[-1])
        if stop_diameter is not None and (self.stop_index is None or not stop_diameter > 0):
            raise ValueError("stop_diameter needs a stop row and a positive diameter")
        self.stop_diameter = (float(stop_diameter) if stop_diameter is not None
                              else self.surfaces[self.stop_index].aperture if self.stop_index is not None else None)
        if iris_blades and (iris_blades < 3 or self.stop_index is None):
            raise ValueError("an iris needs a stop row and at least 3 blades")
        self.iris_blades = int(iris_blades)
        self.iris_rotation_deg = float(iris_rotation_deg)

    def opening_radius(self, index):
        """Radius (mm) of surface `index`'s opening: half the clear aperture, or of the stop's
        diameter (stop_diameter when given)."""
        if index == self.stop_index:
            return self.stop_diameter / 2.0
        return self.surfaces[index].aperture / 2.0

    def edge_sag(self, index):
        """Lens-frame z of the edge of surface `index`'s opening relative to its vertex."""
        c = self.curvature[index]
        a = self.opening_radius(index)
        return c * a * a / (1.0 + math.sqrt(max(0.0, 1.0 - (c * a) ** 2)))

    def passes_opening(self, index, x, y):
        """Whether hit points (x, y) on surface `index` lie in its opening (the iris at the stop)."""
        radius = self.opening_radius(index)
        inside = x * x + y * y <= radius * radius
        if index == self.stop_index and self.iris_blades:
            apothem = radius * math.cos(math.pi / self.iris_blades)
            for k in range(self.iris_blades):
                side = math.radians(self.iris_rotation_deg + 360.0 * k / self.iris_blades)
                inside &= x * math.cos(side) + y * math.sin(side) <= apothem
        return inside


def as_lens(lens):
    """A Lens from a Lens, a lens file's text, or a list of surfaces (Surface rows or dicts)."""
    if isinstance(lens, Lens):
        return lens
    if isinstance(lens, str):
        return Lens(parse_lens_file(lens))
    return Lens(lens)


# ============================================================================================
# Exact sequential ray tracing

class TraceResult(NamedTuple):
    """points: where each ray crossed the last surface it traversed (lens frame, mm);
    directions: unit directions after that surface; passed: bool. Blocked rays have NaN
    points and directions. Shapes follow the input rays: (..., 3) and (...)."""
    points: np.ndarray
    directions: np.ndarray
    passed: np.ndarray


def _intersect_cap(x, y, z, dx, dy, dz, curvature):
    """Parameter t of each ray's first point (t >= T_MIN) on the half of the surface of the
    given curvature that holds the vertex, positions (x, y, z) relative to the vertex, unit
    directions (dx, dy, dz); and whether there is one. The sphere is
    c (x^2 + y^2 + z^2) - 2 z = 0, so along p + t w: c t^2 + 2 b t + e = 0 with
    b = c p.w - w_z, e = c p.p - 2 p_z; its roots are written e / (-b -+ sqrt(b^2 - c e)),
    which has no cancellation for flat or nearly flat surfaces (c = 0 leaves the plane's one
    root, the other becomes infinite)."""
    b = curvature * (x * dx + y * dy + z * dz) - dz
    e = curvature * (x * x + y * y + z * z) - 2.0 * z
    discriminant = b * b - curvature * e
    root = np.sqrt(np.maximum(discriminant, 0.0))
    best = np.full(len(b), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        for t in (e / (-b - root), e / (-b + root)):
            usable = ((discriminant >= 0) & np.isfinite(t) & (t >= T_MIN)
                      & (curvature * (z + t * dz) < 1.0) & (t < best))
            best = np.where(usable, t, best)
    return best, np.isfinite(best)


def _refract(x, y, z, dx, dy, dz, curvature, index_ratio):
    """Snell's law in vector form at hit points (x, y, z) (relative to the vertex) of a surface
    of the given curvature, for unit directions (dx, dy, dz), from index n1 into n2
    (index_ratio = n1 / n2): the new unit directions and whether each ray is transmitted
    (False: total internal reflection). The normal (c x, c y, c z - 1) is turned to face the
    incoming ray; the refracted direction is r w + (r cos_i - cos_t) n."""
    nx, ny, nz = curvature * x, curvature * y, curvature * z - 1.0
    norm = np.sqrt(nx * nx + ny * ny + nz * nz)
    cos_in = -(nx * dx + ny * dy + nz * dz) / norm
    facing = np.where(cos_in < 0, -1.0, 1.0) / norm
    nx, ny, nz = nx * facing, ny * facing, nz * facing
    cos_in = np.abs(cos_in)
    cos_out_squared = 1.0 - index_ratio ** 2 * (1.0 - cos_in ** 2)
    factor = index_ratio * cos_in - np.sqrt(np.maximum(cos_out_squared, 0.0))
    rx, ry, rz = index_ratio * dx + factor * nx, index_ratio * dy + factor * ny, index_ratio * dz + factor * nz
    length = np.sqrt(rx * rx + ry * ry + rz * rz)
    return (rx / length, ry / length, rz / length), cos_out_squared >= 0.0


def _trace(lens, origins, directions, backwards):
    origins, directions = np.broadcast_arrays(np.asarray(origins, float), np.asarray(directions, float))
    shape = origins.shape[:-1]
    flat_origins, flat_directions = origins.reshape(-1, 3), directions.reshape(-1, 3)
    count = len(flat_origins)
    x, y, z = (flat_origins[:, a].copy() for a in range(3))
    length = np.sqrt((flat_directions ** 2).sum(axis=1))
    dx, dy, dz = (flat_directions[:, a] / length for a in range(3))
    ray = np.arange(count)
    order = range(len(lens.surfaces) - 1, -1, -1) if backwards else range(len(lens.surfaces))
    with np.errstate(divide="ignore", invalid="ignore"):
        for i in order:
            c = lens.curvature[i]
            z = z - lens.vertex_z[i]
            t, hit = _intersect_cap(x, y, z, dx, dy, dz, c)
            t = np.where(hit, t, 0.0)
            x, y, z = x + t * dx, y + t * dy, z + t * dz
            keep = hit & lens.passes_opening(i, x, y)
            if not lens.surfaces[i].is_stop:
                n_from, n_to = lens.medium_before[i], lens.medium_after[i]
                if backwards:
                    n_from, n_to = n_to, n_from
                (dx, dy, dz), transmitted = _refract(x, y, z, dx, dy, dz, c, n_from / n_to)
                keep &= transmitted
            z = z + lens.vertex_z[i]
            x, y, z, dx, dy, dz, ray = (a[keep] for a in (x, y, z, dx, dy, dz, ray))
    points = np.full((count, 3), np.nan)
    out_directions = np.full((count, 3), np.nan)
    passed = np.zeros(count, dtype=bool)
    points[ray] = np.stack([x, y, z], axis=1)
    out_directions[ray] = np.stack([dx, dy, dz], axis=1)
    passed[ray] = True
    return TraceResult(points.reshape(shape + (3,)), out_directions.reshape(shape + (3,)), passed.reshape(shape))


def trace_object_to_image(lens, origins, directions):
    """Traces rays (lens frame, mm; directions need not be unit) from the object side through
    every surface, first to last. Returns a TraceResult: the points on the last surface and
    the directions in the image space."""
    return _trace(as_lens(lens), origins, directions, backwards=False)


def trace_image_to_object(lens, origins, directions):
    """Traces rays (lens frame, mm) from the image side through every surface, last to first.
    Returns a TraceResult: the points on the first surface and the directions into the scene."""
    return _trace(as_lens(lens), origins, directions, backwards=True)


# ============================================================================================
# Paraxial data (y-u paraxial ray trace: n' u' = n u - y (n' - n) c, then y += t u')

def _paraxial_ray(lens, height, slope, z_start, surface_range, z_end):
    """A paraxial ray given by its height and slope (dy/dz) on the plane z_start (lens frame),
    in the medium before the first surface of surface_range (consecutive, increasing), traced
    through those surfaces to the plane z_end: its height and slope there."""
    z = z_start
    for i in surface_range:
        height += slope * (lens.vertex_z[i] - z)
        z = lens.vertex_z[i]
        n_before, n_after = lens.medium_before[i], lens.medium_after[i]
        slope = (n_before * slope - height * (n_after - n_before) * lens.curvature[i]) / n_after
    return height + slope * (z_end - z), slope


@dataclass
class ParaxialData:
    """Paraxial (first-order) data of a lens; every z in the lens frame (mm, front vertex 0,
    +z towards the image). The object space is air; image-side lengths are reduced by the image
    space's index where it is not air (rear focal length = n' efl).

    efl: effective focal length 1/power. bfd: rear vertex -> rear focal point, positive when the
    focal point lies behind the rear vertex. ffd: front focal point -> front vertex, positive
    when the focal point lies in front of the front vertex. *_z: positions of the focal
    points, principal planes and pupils. Pupils: images of the stop through the surfaces in
    front of it (entrance) and behind it (exit), with their diameters. f_number = efl /
    entrance_pupil_diameter. stop_index: the stop row, or the surface that limits an axial
    beam from infinity when there is none."""
    efl: float
    bfd: float
    ffd: float
    front_focal_z: float
    rear_focal_z: float
    front_principal_z: float
    rear_principal_z: float
    entrance_pupil_z: float
    entrance_pupil_diameter: float
    exit_pupil_z: float
    exit_pupil_diameter: float
    f_number: float
    stop_index: int


def _limiting_surface(lens):
    """The surface whose opening an axial beam from infinity fills first (smallest ratio of
    opening radius to paraxial marginal height)."""
    ratios = []
    for i in range(len(lens.surfaces)):
        height, _ = _paraxial_ray(lens, 1.0, 0.0, 0.0, range(i), lens.vertex_z[i])
        ratios.append(lens.opening_radius(i) / abs(height) if height != 0 else math.inf)
    return int(np.argmin(ratios))


def paraxial_data(lens):
    """The ParaxialData of a lens (ValueError for an afocal lens or a pupil at infinity)."""
    lens = as_lens(lens)
    everything = range(len(lens.surfaces))
    L = lens.length
    n_image = lens.medium_after[-1]
    parallel_height, parallel_slope = _paraxial_ray(lens, 1.0, 0.0, 0.0, everything, L)
    tilted_height, tilted_slope = _paraxial_ray(lens, 0.0, 1.0, 0.0, everything, L)
    if parallel_slope == 0.0:
        raise ValueError("the lens is afocal")
    efl = -1.0 / (n_image * parallel_slope)
    bfd = -parallel_height / parallel_slope
    # A ray crossing the axis at z_F reaches z = 0 with height -z_F u; it leaves parallel when
    # parallel_slope (-z_F u) + tilted_slope u = 0.
    front_focal_z = tilted_slope / parallel_slope
    stop = lens.stop_index if lens.stop_index is not None else _limiting_surface(lens)
    z_stop = lens.vertex_z[stop]
    stop_radius = lens.opening_radius(stop)
    # Entrance pupil: object-space ray (height y, slope u at z = 0) reaches the stop at
    # y h1 + u h2; the chief ray (through the stop's centre) crosses the axis at z = h2 / h1,
    # and a collimated beam fills the stop with a radius stop_radius / |h1|.
    h1, _ = _paraxial_ray(lens, 1.0, 0.0, 0.0, range(stop), z_stop)
    h2, _ = _paraxial_ray(lens, 0.0, 1.0, 0.0, range(stop), z_stop)
    # Exit pupil: rays leaving the stop's plane, traced to the rear vertex plane.
    edge_height, edge_slope = _paraxial_ray(lens, 1.0, 0.0, z_stop, range(stop, len(lens.surfaces)), L)
    chief_height, chief_slope = _paraxial_ray(lens, 0.0, 1.0, z_stop, range(stop, len(lens.surfaces)), L)
    if h1 == 0.0 or chief_slope == 0.0:
        raise ValueError("a pupil is at infinity")
    exit_pupil_z = L - chief_height / chief_slope
    exit_pupil_diameter = 2.0 * stop_radius * abs(edge_height + edge_slope * (exit_pupil_z - L))
    entrance_pupil_diameter = 2.0 * stop_radius / abs(h1)
    return ParaxialData(
        efl=efl, bfd=bfd, ffd=-front_focal_z, front_focal_z=front_focal_z, rear_focal_z=L + bfd,
        front_principal_z=front_focal_z + efl, rear_principal_z=L + bfd - n_image * efl,
        entrance_pupil_z=h2 / h1, entrance_pupil_diameter=entrance_pupil_diameter,
        exit_pupil_z=exit_pupil_z, exit_pupil_diameter=exit_pupil_diameter,
        f_number=efl / entrance_pupil_diameter, stop_index=stop)


def paraxial_image_distance(lens, object_distance):
    """Paraxial image of an axial object point `object_distance` mm in front of the front vertex
    (math.inf: at infinity): its distance behind the rear vertex (negative: a virtual image in
    front of it; math.inf when the image is at infinity)."""
    lens = as_lens(lens)
    everything = range(len(lens.surfaces))
    if math.isinf(object_distance):
        height, slope = _paraxial_ray(lens, 1.0, 0.0, 0.0, everything, lens.length)
    else:
        height, slope = _paraxial_ray(lens, 0.0, 1.0, -object_distance, everything, lens.length)
    return math.inf if slope == 0.0 else -height / slope


# ============================================================================================
# The camera around the lens

def optics_lens_mirror(points, lens):
    """Lens-frame points -> optics-frame points, and back (the map is its own inverse):
    (x, y, z) -> (x, y, L - z)."""
    p = np.array(points, dtype=float)
    p[..., 2] = as_lens(lens).length - p[..., 2]
    return p


def optics_lens_mirror_directions(directions):
    """Directions between the lens and optics frames (either way): (x, y, z) -> (x, y, -z)."""
    d = np.array(directions, dtype=float)
    d[..., 2] = -d[..., 2]
    return d


def world_to_optics(points, location, right, up, direction, mm_per_unit, lens):
    """World points (scene units, (..., 3)) -> optics frame (mm) of a camera whose `location` is
    the lens's front vertex: ((P - location).(right_u, up_u, dir_u)) mm_per_unit + (0, 0, L)."""
    axes = np.array([np.asarray(v, float) / np.linalg.norm(v) for v in (right, up, direction)])
    offset = np.asarray(points, float) - np.asarray(location, float)
    return offset @ axes.T * mm_per_unit + np.array([0.0, 0.0, as_lens(lens).length])


class Spot(NamedTuple):
    """Centroid (optics frame, mm) of a point's blur spot on the sensor, and how many of the
    sampled rays reached the sensor (NaN centroid when none did)."""
    x: float
    y: float
    count: int


def spot_centroid_no_array(lens, point_optics, D, n_rays):
    """The blur spot on the sensor z = -D (no array) of a scene point given in the optics frame
    (mm, in front of the first surface).

    Rays leave the point towards a square grid of about n_rays points filling a disc on the
    front vertex plane (lens frame z = 0) that holds every ray that can meet the first surface
    inside its clear aperture (bound: the ray from P to a hit point H crosses z = 0 at
    P + (H - P) s, s = -P_z / (H_z - P_z), and H_z lies between the vertex and the edge of the
    cap). Each grid point stands for the same area, so the centroid of the rays that pass
    every surface is the irradiance centroid of the spot (equal areas on any plane
    perpendicular to the axis seen from P are equal weights)."""
    lens = as_lens(lens)
    source = optics_lens_mirror(point_optics, lens)
    edge_z = lens.edge_sag(0)
    nearest_z, farthest_z = min(0.0, edge_z), max(0.0, edge_z)
    if not source[2] < nearest_z:
        raise ValueError("the point must lie in front of the first surface")
    off_axis = math.hypot(source[0], source[1])
    first_radius = lens.opening_radius(0)
    radius = max(off_axis * abs(1.0 - s) + s * first_radius
                 for s in (-source[2] / (hit_z - source[2]) for hit_z in (nearest_z, farthest_z)))
    radius = radius * (1.0 + 1e-9) + 1e-9
    per_axis = max(1, int(math.ceil(math.sqrt(4.0 * n_rays / math.pi))))
    centres = ((np.arange(per_axis) + 0.5) / per_axis * 2.0 - 1.0) * radius
    gx, gy = np.meshgrid(centres, centres)
    in_disc = gx * gx + gy * gy <= radius * radius
    targets = np.stack([gx[in_disc], gy[in_disc], np.zeros(in_disc.sum())], axis=1)
    result = trace_object_to_image(lens, source, targets - source)
    points, directions = result.points[result.passed], result.directions[result.passed]
    forward = directions[:, 2] > 0
    points, directions = points[forward], directions[forward]
    t = (lens.length + D - points[:, 2]) / directions[:, 2]
    x = points[:, 0] + t * directions[:, 0]
    y = points[:, 1] + t * directions[:, 1]
    if len(x) == 0:
        return Spot(math.nan, math.nan, 0)
    return Spot(float(x.mean()), float(y.mean()), int(len(x)))


def white_image_pinhole_array(lens, D, d, pitch, W, H, sx, sy, samples_per_axis):
    """The image (H x W floats) of a uniformly white scene (radiance 1 on every ray that leaves
    the front of the lens) through a rectangular array of pinhole microlenses: array at z = -D,
    sensor at z = -(D + d), pixels as in the module docstring.

    Each pixel is sampled at samples_per_axis^2 stratified points S, the centres of an n x n
    grid of equal sub-squares of the pixel. For each S, every microlens k whose ray S -> centre_k
    passes the whole lens (traced from the image side: clear apertures, stop, iris, total
    internal reflection) adds 1; the pixel's value is that sum averaged over its points S.

    Which lenses are tried: a ray that passes must meet the last surface inside its opening,
    at a point X with |X_xy| <= a (the opening's radius) and z between 0 and the opening edge's
    optics-frame z. The ray S -> X crosses the array at S (1 - s) + X s with
    s = d / (D + d + X_z), so the centre of every lens that can pass lies within
    a s_max + |S| (s_max - s_min) / 2 of S (1 - s_mid). Every lens in that disc is traced, so no
    lens is missed however much the microimages overlap."""
    lens = as_lens(lens)
    last = len(lens.surfaces) - 1
    opening = lens.opening_radius(last)
    edge_optics_z = -lens.edge_sag(last)
    lowest_z, highest_z = min(0.0, edge_optics_z), max(0.0, edge_optics_z)
    if not lowest_z > -D:
        raise ValueError("the last surface reaches the array plane")
    s_min, s_max = d / (D + d + highest_z), d / (D + d + lowest_z)
    s_mid = 0.5 * (s_min + s_max)
    n = int(samples_per_axis)
    fractions = (np.arange(n) + 0.5) / n
    # x of the points of one sub-row of a pixel row, pixel by pixel, and their pixel columns
    point_x = (-((np.arange(W)[:, None] + fractions[None, :]) - W / 2.0) * sx).ravel()
    point_column = np.repeat(np.arange(W), n)
    sensor_reach = math.hypot(W * sx, H * sy) / 2.0     # no point S lies farther from the axis
    window = int(math.ceil((opening * s_max + sensor_reach * (s_max - s_min) / 2.0) / pitch + 0.5))
    offsets = np.arange(-window, window + 1)
    offset_k, offset_l = (a.ravel() for a in np.meshgrid(offsets, offsets))
    image = np.zeros((H, W))
    for j in range(H):
        row_y = ((j + fractions) - H / 2.0) * sy
        row_points_x = np.tile(point_x, n)                  # every sub-row of the pixel row
        row_points_y = np.repeat(row_y, len(point_x))
        row_points_column = np.tile(point_column, n)
        sums = np.zeros(W)
        block = max(1, CANDIDATES_PER_BLOCK // len(offset_k))
        for start in range(0, len(row_points_x), block):
            px, py = row_points_x[start:start + block], row_points_y[start:start + block]
            centre_x, centre_y = px * (1.0 - s_mid), py * (1.0 - s_mid)
            reach = opening * s_max + np.hypot(px, py) * (s_max - s_min) / 2.0
            lens_x = (np.round(centre_x / pitch)[:, None] + offset_k[None, :]) * pitch
            lens_y = (np.round(centre_y / pitch)[:, None] + offset_l[None, :]) * pitch
            near = ((lens_x - centre_x[:, None]) ** 2 + (lens_y - centre_y[:, None]) ** 2
                    <= (reach[:, None] * (1.0 + 1e-9)) ** 2)
            point_index, candidate = np.nonzero(near)
            origins = np.stack([px[point_index], py[point_index],
                                np.full(len(point_index), lens.length + D + d)], axis=1)
            towards = np.stack([lens_x[point_index, candidate] - px[point_index],
                                lens_y[point_index, candidate] - py[point_index],
                                np.full(len(point_index), -d)], axis=1)
            passed = trace_image_to_object(lens, origins, towards).passed
            sums += np.bincount(row_points_column[start:start + block][point_index[passed]], minlength=W)
        image[j] = sums / (n * n)
    return image


def relative_lit_area_no_array(lens, D, points_xy, samples_per_axis):
    """For sensor points S = (x, y) on the plane D behind the rear vertex (no array), the area of
    the exit pupil's plane through which a ray from S passes the whole lens (clear apertures,
    stop, iris, total internal reflection), over the paraxial exit pupil's area: what a pixel
    at S records in a uniformly white scene (radiance 1). Returns an array of len(points_xy).

    The area is counted on a samples_per_axis^2 grid of cell centres over a square that holds
    every ray that can pass: such a ray meets the last surface inside its opening, at a point X
    with |X_xy| <= a and lens-frame z between the vertex and the opening's edge, so it crosses
    the exit pupil's plane within a s_max + |S| (s_max - s_min) / 2 of S (1 - s_mid), where s is
    the fraction of the way from S to X at which the plane lies."""
    lens = as_lens(lens)
    data = paraxial_data(lens)
    last = len(lens.surfaces) - 1
    a = lens.opening_radius(last)
    sensor_z = lens.length + D
    rim_z = [lens.length, lens.length + lens.edge_sag(last)]
    fractions = [(sensor_z - data.exit_pupil_z) / (sensor_z - z) for z in rim_z]
    s_min, s_max = min(fractions), max(fractions)
    s_mid = 0.5 * (s_min + s_max)
    n = int(samples_per_axis)
    grid = (np.arange(n) + 0.5) / n * 2.0 - 1.0
    gx, gy = (g.ravel() for g in np.meshgrid(grid, grid))
    pupil_area = math.pi * (data.exit_pupil_diameter / 2.0) ** 2
    out = []
    for x, y in points_xy:
        half = a * s_max + math.hypot(x, y) * (s_max - s_min) / 2.0 + 1e-6
        cx, cy = x * (1.0 - s_mid), y * (1.0 - s_mid)
        targets = np.stack([cx + half * gx, cy + half * gy, np.full(gx.shape, data.exit_pupil_z)], axis=1)
        origins = np.tile([x, y, sensor_z], (len(gx), 1))
        passed = trace_image_to_object(lens, origins, targets - origins).passed
        out.append(passed.sum() * (2.0 * half / n) ** 2 / pupil_area)
    return np.array(out)
