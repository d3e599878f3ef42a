// SPDX-License-Identifier: AGPL-3.0-or-later
// Ray generation through ideal thin lenses and pinholes, forward projection, microimage lattice.

#include "plenoptic_optics.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace plenoptic {

namespace {

// Homogeneous point (x, y, z, w): the point (x/w, y/w, z/w), or the direction (x, y, z) if w = 0.
struct Homogeneous {
    Vec3 xyz;
    double w;
};

// Candidate lenses are enumerated in a box of array-local coordinates.
struct Box {
    bool valid;
    double x0, x1, y0, y1;
};

// Bound on the lenses forward_project examines for one point, so no input can make it hang.
const long long kMaxForwardLenses = 1LL << 24;

Vec3 to_local(const Model& m, Vec3 q) { return mul_transposed(m.pose.rotation, q - m.pose.centre_mm); }
Vec3 to_optics(const Model& m, Vec3 local) { return m.pose.centre_mm + mul(m.pose.rotation, local); }

double microlens_focal(const Model& m, LensIndex lens)
{
    return m.microlens_focal_mm[lens_type(lens, m.lens_type_count)];
}

// Whether (x, y) lies in the disc of this radius about the origin: squares where they cannot
// overflow (cheaper than hypot: this runs for every ray), hypot for absurdly large apertures.
bool inside_disc(double x, double y, double radius)
{
    if (radius < 1e150)
        return x * x + y * y <= radius * radius;  // an overflowing x * x is +inf: outside, as it should be
    return std::hypot(x, y) <= radius;
}

bool finish(Vec3 origin, Vec3 direction, OpticsRay* out)
{
    const Vec3 unit = normalized(direction);
    if (!is_finite(origin) || !is_finite(unit))
        return false;
    // A lens of high power, or a steeply tilted one, can bend a ray back towards the camera:
    // it would meet the camera body, not the scene.
    if (!(unit.z > 0))
        return false;
    out->origin_mm[0] = origin.x;
    out->origin_mm[1] = origin.y;
    out->origin_mm[2] = origin.z;
    out->dir[0] = unit.x;
    out->dir[1] = unit.y;
    out->dir[2] = unit.z;
    return true;
}

// Intersection of the line (main-lens centre -> p), or the vertical line through p when there is
// no main lens, with the array plane; array-local coordinates.
bool project_to_array(const Model& m, Vec3 p, Vec2* local)
{
    const Vec3 n = m.pose.normal;
    Vec3 q;
    if (m.main_lens == MainLensType::None) {
        if (!(n.z > 0))
            return false;
        q = Vec3{p.x, p.y, p.z + dot(n, m.pose.centre_mm - p) / n.z};
    } else {
        const double along = dot(n, p);
        const double s = dot(n, m.pose.centre_mm) / along;
        if (!(s > 0) || !std::isfinite(s))
            return false;
        q = s * p;
    }
    const Vec3 l = to_local(m, q);
    *local = Vec2{l.x, l.y};
    return is_finite(*local);
}

// Ray from sensor point p through the microlens `lens` to the pinhole main lens at the origin.
// The microlens images the pinhole O to the homogeneous point I = (o, 1 - o_z/f) (lens-relative
// coordinates); every ray from p aimed at I leaves the lens through O. No division by
// (1 + D/d - D/f), so near-degenerate set-ups only block rays.
bool through_pinhole_main(const Model& m, Vec3 p, LensIndex lens, bool check_cell, OpticsRay* out)
{
    const Vec2 c = lens_centre(m.grid, m.pitch_mm, lens);
    const double f = microlens_focal(m, lens);
    const Vec3 o = to_local(m, Vec3{0, 0, 0});
    const Vec3 s = to_local(m, p);
    if (!(o.z > 0) || !(s.z < 0))
        return false;
    const Vec3 o_rel{o.x - c.x, o.y - c.y, o.z};
    const Vec3 p_rel{s.x - c.x, s.y - c.y, s.z};
    const double w = 1 - o_rel.z / f;
    Vec3 along = o_rel - w * p_rel;  // direction of the line p -> I
    if (along.z < 0)
        along = -along;
    if (!(along.z > 0))
        return false;
    const double t = -p_rel.z / along.z;
    const double hx = p_rel.x + t * along.x;
    const double hy = p_rel.y + t * along.y;
    if (check_cell && nearest_lens(m.grid, m.pitch_mm, c.x + hx, c.y + hy) != lens)
        return false;
    const Vec3 local_out{along.x / along.z - hx / f, along.y / along.z - hy / f, 1};
    return finish(Vec3{0, 0, 0}, mul(m.pose.rotation, local_out), out);
}

// The whole camera for one sensor point and one aperture sample (lens_u, lens_v).
bool trace_sensor_point(const Model& m, Vec3 p, const LensIndex* forced, double lens_u, double lens_v,
                        bool check_apertures, OpticsRay* out)
{
    if (m.grid == GridType::None) {
        if (m.main_lens == MainLensType::Pinhole)
            return finish(Vec3{0, 0, 0}, -p, out);
        // Thin main lens: a point on the aperture disc; the ray p -> m with unit z component
        // is refracted by w' = w - m / F.
        const Vec2 disc = concentric_disc(lens_u, lens_v);
        const double radius = 0.5 * m.aperture_mm;
        const Vec3 on_lens{radius * disc.x, radius * disc.y, 0};
        const double rise = -p.z;  // = D
        const double wx = (on_lens.x - p.x) / rise - on_lens.x / m.focal_length_mm;
        const double wy = (on_lens.y - p.y) / rise - on_lens.y / m.focal_length_mm;
        return finish(on_lens, Vec3{wx, wy, 1}, out);
    }

    LensIndex lens;
    if (forced) {
        lens = *forced;
    } else {
        Vec2 q;
        if (!project_to_array(m, p, &q))
            return false;
        lens = nearest_lens(m.grid, m.pitch_mm, q.x, q.y);
    }

    if (m.microlens == MicrolensType::ThinLens && m.main_lens == MainLensType::Pinhole)
        return through_pinhole_main(m, p, lens, check_apertures, out);

    const Vec2 c_local = lens_centre(m.grid, m.pitch_mm, lens);
    Vec3 leave;      // where the ray leaves the array
    Vec3 direction;  // after the microlens, optics frame, any length
    if (m.microlens == MicrolensType::Pinhole) {
        leave = to_optics(m, Vec3{c_local.x, c_local.y, 0});
        direction = leave - p;
        if (!(dot(direction, m.pose.normal) > 0))
            return false;  // the sensor point is not behind the array
    } else {
        // A point of the lens cell; refraction in the array's own frame, with the direction
        // normalised to unit local z: w' = w - (h - c) / f.
        const Vec2 offset = sample_cell_uniform(m.grid, m.pitch_mm, lens_u, lens_v);
        leave = to_optics(m, Vec3{c_local.x + offset.x, c_local.y + offset.y, 0});
        const Vec3 w = mul_transposed(m.pose.rotation, leave - p);
        if (!(w.z > 0))
            return false;
        const double f = microlens_focal(m, lens);
        const Vec3 refracted{w.x / w.z - offset.x / f, w.y / w.z - offset.y / f, 1};
        direction = mul(m.pose.rotation, refracted);
    }

    if (m.main_lens == MainLensType::None)
        return finish(leave, direction, out);
    if (m.main_lens == MainLensType::Pinhole)
        return false;  // pinhole + pinhole: refused at parse time, no ray passes both points

    // On to the main-lens plane z = 0, then w' = w - m / F.
    if (!(direction.z > 0) || !(leave.z < 0))
        return false;
    const double travel = -leave.z / direction.z;
    const double mx = leave.x + travel * direction.x;
    const double my = leave.y + travel * direction.y;
    const double radius = 0.5 * m.aperture_mm;
    if (check_apertures && !inside_disc(mx, my, radius))
        return false;  // misses the main-lens aperture: carries no light
    const double wx = direction.x / direction.z - mx / m.focal_length_mm;
    const double wy = direction.y / direction.z - my / m.focal_length_mm;
    return finish(Vec3{mx, my, 0}, Vec3{wx, wy, 1}, out);
}

// Whether light through `lens` can reach some point of the pixel centred at p. With k = D/d
// measured at the lens: the chief ray p -> c meets the main-lens plane at m0 = c (1 + k) - p k
// (exact, tilted or not); a ray from sensor point p' through cell point h arrives at
// m0 + (h - c) g - (p' - p) k with g = 1 + k - D/f for an array parallel to the sensor, so the
// lens reaches the pixel iff that region meets the aperture disc. Conservative: circumradius for
// the cell, half the pixel diagonal for the pixel; for a slightly tilted array the spread terms get
// a margin that grows with the tilt (validated against brute force in the unit tests).
bool lens_reaches_pixel(const Model& m, LensIndex lens, Vec3 p)
{
    const Vec3 c = lens_centre_mm(m, lens);
    const double main_distance = -c.z;
    const double array_distance = c.z - m.sensor_z_mm;
    if (!(main_distance > 0) || !(array_distance > 0))
        return true;
    const double k = main_distance / array_distance;
    const double mx = c.x * (1 + k) - p.x * k;
    const double my = c.y * (1 + k) - p.y * k;
    double spread = 0.5 * std::hypot(m.pixel_size_mm[0], m.pixel_size_mm[1]) * k;
    if (m.microlens == MicrolensType::ThinLens)
        spread += m.cell_circumradius_mm * std::fabs(1 + k - main_distance / microlens_focal(m, lens));
    if (m.pose.tilted)
        spread *= 1.25 + 4 * m.pose.tilt_sine;
    return std::hypot(mx, my) <= (0.5 * m.aperture_mm + spread) * (1 + 1e-9);
}

// Sensor hit of a ray arriving at array point h (optics frame) with direction `towards_sensor`,
// refracted by `lens` (the same rule w' = w - (h - c)/f with w normalised to unit travel along the
// normal).
bool sensor_hit_through_lens(const Model& m, LensIndex lens, Vec3 h, Vec3 towards_sensor, Vec3* hit)
{
    Vec3 direction = towards_sensor;
    if (m.microlens == MicrolensType::ThinLens) {
        const Vec3 w = mul_transposed(m.pose.rotation, towards_sensor);
        if (!(w.z < 0))
            return false;
        const Vec3 h_local = to_local(m, h);
        const Vec2 c = lens_centre(m.grid, m.pitch_mm, lens);
        const double f = microlens_focal(m, lens);
        const Vec3 out_local{w.x / -w.z - (h_local.x - c.x) / f, w.y / -w.z - (h_local.y - c.y) / f, -1};
        direction = mul(m.pose.rotation, out_local);
    }
    if (!(direction.z < 0))
        return false;
    const double travel = (m.sensor_z_mm - h.z) / direction.z;
    if (!(travel > 0))
        return false;
    *hit = h + travel * direction;
    return is_finite(*hit);
}

// Line through homogeneous point a and point b, met with the plane n . x = n . point.
bool line_meets_plane(Homogeneous a, Vec3 b, Vec3 n, Vec3 point, Homogeneous* out)
{
    const double alpha = dot(n, point) - dot(n, b);
    const double beta = dot(n, a.xyz) - a.w * dot(n, point);
    out->xyz = alpha * a.xyz + beta * b;
    out->w = alpha * a.w + beta;
    return out->w != 0 && is_finite(out->xyz) && std::isfinite(out->w);
}

Box intersect(Box a, Box b)
{
    if (!a.valid)
        return b;
    if (!b.valid)
        return a;
    Box out{true, std::max(a.x0, b.x0), std::min(a.x1, b.x1), std::max(a.y0, b.y0), std::min(a.y1, b.y1)};
    return out;
}

Box grow(Box box, double margin)
{
    box.x0 -= margin;
    box.x1 += margin;
    box.y0 -= margin;
    box.y1 += margin;
    return box;
}

void include(Box* box, Vec2 p)
{
    if (!box->valid) {
        *box = Box{true, p.x, p.x, p.y, p.y};
        return;
    }
    box->x0 = std::min(box->x0, p.x);
    box->x1 = std::max(box->x1, p.x);
    box->y0 = std::min(box->y0, p.y);
    box->y1 = std::max(box->y1, p.y);
}

// The part of the array plane whose lenses can image into the picture: the image corners
// projected onto the array, grown by two pitches. Invalid if a corner does not project.
Box sensor_box(const Model& m, int W, int H)
{
    Box box{false, 0, 0, 0, 0};
    const double corners[4][2] = {{0, 0}, {double(W), 0}, {0, double(H)}, {double(W), double(H)}};
    for (int i = 0; i < 4; ++i) {
        Vec2 q;
        if (!project_to_array(m, sensor_point(m, W, H, corners[i][0], corners[i][1]), &q))
            return Box{false, 0, 0, 0, 0};
        include(&box, q);
    }
    return grow(box, 2 * m.pitch_mm);
}

// Calls visit(lens) for every lens whose centre lies in the box (array-local), row by row.
template <class Visit>
void for_each_lens_in_box(const Model& m, Box box, Visit visit)
{
    if (!box.valid || !(box.x0 <= box.x1) || !(box.y0 <= box.y1))
        return;
    const double row = row_spacing(m.grid, m.pitch_mm);
    const double rows = std::floor(box.y1 / row) - std::ceil(box.y0 / row) + 1;
    const double columns = (box.x1 - box.x0) / m.pitch_mm + 2;
    if (!(rows * columns <= double(kMaxForwardLenses)))
        return;  // absurd sizes: give no hits rather than hang
    const double limit = double(kMaxLensIndex);
    if (!(std::fabs(box.y0 / row) < limit && std::fabs(box.y1 / row) < limit &&
          std::fabs(box.x0 / m.pitch_mm) < limit && std::fabs(box.x1 / m.pitch_mm) < limit))
        return;
    const std::int64_t l0 = std::int64_t(std::ceil(box.y0 / row));
    const std::int64_t l1 = std::int64_t(std::floor(box.y1 / row));
    for (std::int64_t l = l0; l <= l1; ++l) {
        const double shift = (m.grid == GridType::Hexagonal && floor_mod(l, 2) == 1) ? 0.5 : 0.0;
        const std::int64_t k0 = std::int64_t(std::ceil(box.x0 / m.pitch_mm - shift));
        const std::int64_t k1 = std::int64_t(std::floor(box.x1 / m.pitch_mm - shift));
        for (std::int64_t k = k0; k <= k1; ++k)
            visit(LensIndex{k, l});
    }
}

// Distance from the origin to a convex polygon (0 when inside), corners in either orientation.
double distance_to_origin(const Vec2* corner, int count)
{
    bool all_left = true, all_right = true;
    double best = INFINITY;
    for (int i = 0; i < count; ++i) {
        const Vec2 a = corner[i];
        const Vec2 b = corner[(i + 1) % count];
        const double side = cross(b - a, Vec2{0, 0} - a);
        all_left = all_left && side >= 0;
        all_right = all_right && side <= 0;
        const Vec2 ab = b - a;
        const double len2 = dot(ab, ab);
        double t = len2 > 0 ? -dot(a, ab) / len2 : 0;
        t = std::min(1.0, std::max(0.0, t));
        best = std::min(best, length(a + t * ab));
    }
    return (all_left || all_right) ? 0.0 : best;
}

// Whether some ray from the object (thin-lens image `image`) through the main aperture passes
// through the lens's cell (its centre only, for pinholes): the cell, projected from the image
// point onto the main-lens plane, must meet the aperture disc.
bool lens_sees(const Model& m, Homogeneous image, LensIndex lens)
{
    const Vec2 c = lens_centre(m.grid, m.pitch_mm, lens);
    Vec2 local[6];
    int count = 1;
    local[0] = Vec2{0, 0};
    if (m.microlens == MicrolensType::ThinLens)
        count = cell_polygon(m.grid, m.pitch_mm, local);
    Vec2 projected[6];
    double first_sign = 0;
    for (int i = 0; i < count; ++i) {
        const Vec3 corner = to_optics(m, Vec3{c.x + local[i].x, c.y + local[i].y, 0});
        Homogeneous hit;
        if (!line_meets_plane(image, corner, Vec3{0, 0, 1}, Vec3{0, 0, 0}, &hit))
            return m.microlens == MicrolensType::ThinLens;  // projection unbounded: keep (conservative)
        const double sign = hit.w > 0 ? 1 : -1;
        if (i == 0)
            first_sign = sign;
        else if (sign != first_sign)
            return true;  // the cell straddles the vanishing line: unbounded, keep
        projected[i] = Vec2{hit.xyz.x / hit.w, hit.xyz.y / hit.w};
    }
    const double radius = 0.5 * m.aperture_mm;
    if (count == 1)
        return dot(projected[0], projected[0]) <= radius * radius;
    return distance_to_origin(projected, count) <= radius;
}

// The cone of light from the main aperture to the point's image X', met with the array plane:
// a polygon of kFootprintSides corners in array-local coordinates. False when the cone does not
// cross the plane as a bounded region.
const int kFootprintSides = 96;

bool cone_footprint(const Model& m, Homogeneous image, Vec2 footprint[kFootprintSides])
{
    const double r = 0.5 * m.aperture_mm;
    double first_sign = 0;
    for (int i = 0; i < kFootprintSides; ++i) {
        const double angle = 2 * 3.14159265358979323846 * i / kFootprintSides;
        Homogeneous hit;
        if (!line_meets_plane(image, Vec3{r * std::cos(angle), r * std::sin(angle), 0}, m.pose.normal,
                              m.pose.centre_mm, &hit))
            return false;
        const double sign = hit.w > 0 ? 1 : -1;
        if (i == 0)
            first_sign = sign;
        else if (sign != first_sign)
            return false;
        const Vec3 local = to_local(m, (1 / hit.w) * hit.xyz);
        footprint[i] = Vec2{local.x, local.y};
    }
    return true;
}

// Centroid of (convex polygon `subject`) clipped by the convex polygon `clip` (counter-clockwise);
// false when they do not overlap. Sutherland-Hodgman, then the shoelace centroid.
bool clipped_centroid(const Vec2* subject, int subject_count, const Vec2* clip, int clip_count, Vec2* centroid)
{
    std::vector<Vec2> poly(subject, subject + subject_count), next;
    // The footprint may wind either way; the clip test below assumes counter-clockwise.
    double area2 = 0;
    for (size_t i = 0; i < poly.size(); ++i)
        area2 += cross(poly[i], poly[(i + 1) % poly.size()]);
    if (area2 < 0)
        std::reverse(poly.begin(), poly.end());
    for (int e = 0; e < clip_count && !poly.empty(); ++e) {
        const Vec2 a = clip[e], b = clip[(e + 1) % clip_count];
        next.clear();
        for (size_t i = 0; i < poly.size(); ++i) {
            const Vec2 p = poly[i], q = poly[(i + 1) % poly.size()];
            const double sp = cross(b - a, p - a), sq = cross(b - a, q - a);
            if (sp >= 0)
                next.push_back(p);
            if ((sp >= 0) != (sq >= 0)) {
                const double t = sp / (sp - sq);
                next.push_back(p + t * (q - p));
            }
        }
        poly.swap(next);
    }
    double area = 0, cx = 0, cy = 0;
    for (size_t i = 0; i < poly.size(); ++i) {
        const Vec2 p = poly[i], q = poly[(i + 1) % poly.size()];
        const double w = cross(p, q);
        area += w;
        cx += (p.x + q.x) * w;
        cy += (p.y + q.y) * w;
    }
    if (!(std::fabs(area) > 0))
        return false;
    *centroid = Vec2{cx / (3 * area), cy / (3 * area)};
    return is_finite(*centroid);
}

void add_hit_if_own(const Model& m, int W, int H, LensIndex lens, Vec3 hit, std::vector<PixelHit>* hits)
{
    double u, v;
    if (!sensor_to_pixel(m, W, H, hit.x, hit.y, &u, &v))
        return;
    LensIndex owner;
    if (!own_lens(m, Vec3{hit.x, hit.y, m.sensor_z_mm}, &owner) || owner != lens)
        return;  // outside this lens's microimage cell
    hits->push_back(PixelHit{lens, u, v});
}

void project_through_thin_main(const Model& m, int W, int H, Vec3 point, std::vector<PixelHit>* hits)
{
    const Homogeneous image{point, 1 - point.z / m.focal_length_mm};
    const Vec3 n = m.pose.normal;
    const Vec3 centre = m.pose.centre_mm;

    // Footprint of the cone (main aperture -> image) on the array: project the aperture's
    // bounding square from the image point; bounded when all four corners project to one side.
    Box footprint{false, 0, 0, 0, 0};
    const double r = 0.5 * m.aperture_mm;
    const double square[4][2] = {{-r, -r}, {r, -r}, {r, r}, {-r, r}};
    double first_sign = 0;
    bool bounded = true;
    for (int i = 0; i < 4 && bounded; ++i) {
        Homogeneous hit;
        if (!line_meets_plane(image, Vec3{square[i][0], square[i][1], 0}, n, centre, &hit)) {
            bounded = false;
            break;
        }
        const double sign = hit.w > 0 ? 1 : -1;
        if (i == 0)
            first_sign = sign;
        bounded = sign == first_sign;
        const Vec3 local = to_local(m, (1 / hit.w) * hit.xyz);
        include(&footprint, Vec2{local.x, local.y});
    }
    if (!bounded)
        footprint.valid = false;
    else
        footprint = grow(footprint, m.cell_circumradius_mm);
    const Box box = intersect(footprint, sensor_box(m, W, H));
    if (!box.valid)
        return;

    // Is the image point on the array plane? Then the chief line through a lens centre runs in
    // the plane and the lens containing X' images the point along the main-lens chief ray.
    const double offset = dot(n, image.xyz) - image.w * dot(n, centre);
    const bool on_array = std::fabs(offset) <= 1e-12 * (std::fabs(dot(n, image.xyz)) + std::fabs(image.w * dot(n, centre)));

    if (on_array) {
        // The cone's footprint is the single point X' = h: only the lens containing it sees the
        // point, and the image's centre is the main-lens chief ray O -> h, refracted there.
        if (image.w == 0)
            return;
        const Vec3 h = (1 / image.w) * image.xyz;
        const Vec3 h_local = to_local(m, h);
        const LensIndex lens = nearest_lens(m.grid, m.pitch_mm, h_local.x, h_local.y);
        if (m.microlens == MicrolensType::Pinhole && length(h - lens_centre_mm(m, lens)) > 1e-9 * m.pitch_mm)
            return;  // a pinhole passes light only at its centre
        Vec3 hit;
        if (sensor_hit_through_lens(m, lens, h, h, &hit))
            add_hit_if_own(m, W, H, lens, hit, hits);
        return;
    }

    // Thin microlenses: the point's light through a lens is the part of the cone's footprint
    // inside that lens's cell; its image is where that light lands, centred on the ray from X'
    // through the centroid of that part (the map from array to sensor is affine, so centroids
    // map to centroids). A whole cell gives the Institut Pascal line through the lens centre;
    // plenoptic 1.0 cameras, whose footprints are small, need the partial cells.
    Vec2 cone[kFootprintSides];
    const bool thin_microlenses = m.microlens == MicrolensType::ThinLens;
    const bool use_footprint = thin_microlenses && cone_footprint(m, image, cone);
    Vec2 cell[6];
    const int cell_count = thin_microlenses ? cell_polygon(m.grid, m.pitch_mm, cell) : 0;

    for_each_lens_in_box(m, box, [&](LensIndex lens) {
        if (!lens_sees(m, image, lens))
            return;
        if (use_footprint) {
            const Vec2 c = lens_centre(m.grid, m.pitch_mm, lens);
            Vec2 corners[6];
            for (int i = 0; i < cell_count; ++i)
                corners[i] = c + cell[i];
            Vec2 centroid;
            if (!clipped_centroid(cone, kFootprintSides, corners, cell_count, &centroid))
                return;
            const Vec3 h = to_optics(m, Vec3{centroid.x, centroid.y, 0});
            // Direction of the light at h, towards the sensor: along the line X' - h.
            Vec3 towards = image.w == 0 ? image.xyz : (1 / image.w) * image.xyz - h;
            if (dot(towards, m.pose.normal) > 0)
                towards = -towards;
            Vec3 hit;
            if (sensor_hit_through_lens(m, lens, h, towards, &hit))
                add_hit_if_own(m, W, H, lens, hit, hits);
            return;
        }
        // Line from X' through the lens centre (its chief ray), met with the sensor plane.
        Homogeneous meet;
        if (!line_meets_plane(image, lens_centre_mm(m, lens), Vec3{0, 0, 1}, Vec3{0, 0, m.sensor_z_mm}, &meet))
            return;
        const Vec3 hit = (1 / meet.w) * meet.xyz;
        if (is_finite(hit))
            add_hit_if_own(m, W, H, lens, hit, hits);
    });
}

void project_through_pinhole_main(const Model& m, int W, int H, Vec3 point, std::vector<PixelHit>* hits)
{
    if (m.microlens == MicrolensType::Pinhole)
        return;
    // The single ray: point -> pinhole -> array.
    const Vec3 towards_sensor = -point;
    const double along = dot(m.pose.normal, towards_sensor);
    const double t = dot(m.pose.normal, m.pose.centre_mm) / along;
    if (!(t > 0) || !std::isfinite(t))
        return;
    const Vec3 h = t * towards_sensor;
    const Vec3 h_local = to_local(m, h);
    const LensIndex lens = nearest_lens(m.grid, m.pitch_mm, h_local.x, h_local.y);
    Vec3 hit;
    if (sensor_hit_through_lens(m, lens, h, towards_sensor, &hit))
        add_hit_if_own(m, W, H, lens, hit, hits);
}

void project_without_main(const Model& m, int W, int H, Vec3 point, std::vector<PixelHit>* hits)
{
    const Vec3 local = to_local(m, point);
    if (!(local.z > 0))
        return;  // behind the array
    Box box = sensor_box(m, W, H);
    if (!m.pose.tilted) {
        // A lens images the point into its own cell only if the point is within
        // R (z + d) / d of the lens centre, sideways.
        const double reach = m.cell_circumradius_mm * (local.z / effective_array_distance_mm(m) + 1) +
                             m.cell_circumradius_mm;
        box = intersect(box, Box{true, local.x - reach, local.x + reach, local.y - reach, local.y + reach});
    }
    for_each_lens_in_box(m, box, [&](LensIndex lens) {
        const Vec3 c = lens_centre_mm(m, lens);
        Vec3 hit;
        if (sensor_hit_through_lens(m, lens, c, c - point, &hit))
            add_hit_if_own(m, W, H, lens, hit, hits);
    });
}

// Pixel coordinates (centre convention) of an array-local point projected onto the sensor.
bool local_to_px(const Model& m, int W, int H, Vec2 local, Vec2* px)
{
    const Vec3 c = to_optics(m, Vec3{local.x, local.y, 0});
    double x = c.x, y = c.y;
    if (m.main_lens != MainLensType::None) {
        if (!(c.z < 0))
            return false;
        const double s = m.sensor_z_mm / c.z;
        x *= s;
        y *= s;
    }
    sensor_to_pixel(m, W, H, x, y, &px->x, &px->y);
    return is_finite(*px);
}

// x modulo m in [0, m).
double wrap(double x, double m)
{
    const double r = x - m * std::floor(x / m);
    return (r >= m || r < 0) ? 0.0 : r;
}

// LFToolbox's LensletGridModel, normalised the way LFBuildLensletGridModel normalises its own
// estimate: the grid origin's projections on the rotated axes are reduced to [0, HSpacing/2) and
// [0, VSpacing) (1-based pixels), and the row parity decides FirstPosShiftRow. A perfect
// LFToolbox estimate of the rendered white image gives these same numbers.
void fit_lftoolbox(const Model& m, int W, int H, MicroimageLattice* lattice)
{
    lattice->lftoolbox_valid = false;
    const Vec2 a{lattice->basis_a_px[0], lattice->basis_a_px[1]};
    const Vec2 b{lattice->basis_b_px[0], lattice->basis_b_px[1]};
    const double h_spacing = length(a);
    if (!(h_spacing > 0) || !std::isfinite(h_spacing))
        return;
    // Columns run along +-a, whichever points right; rows go down the image.
    const double column_sign = (a.x > 0 || (a.x == 0 && a.y > 0)) ? 1 : -1;
    const Vec2 e{column_sign * a.x / h_spacing, column_sign * a.y / h_spacing};
    const Vec2 down{-e.y, e.x};
    const double v_spacing = std::fabs(dot(b, down));
    if (!(v_spacing > 0) || !std::isfinite(v_spacing))
        return;
    // Absurdly small microimages: no meaningful grid (and the counts would overflow).
    if (!(W / h_spacing < 1e9 && H / v_spacing < 1e9))
        return;

    const bool hexagonal = m.grid == GridType::Hexagonal;
    const Vec2 reference{lattice->origin_px[0] + 1, lattice->origin_px[1] + 1};  // lens (0, 0), 1-based
    double h_proj = dot(reference, e);
    const double v_proj = dot(reference, down);
    // Lens (0, 0) absurdly far outside the image: the row counts below would overflow.
    if (!(std::fabs(v_proj / v_spacing) < 1e15 && std::fabs(h_proj / h_spacing) < 1e15))
        return;
    const double new_v = wrap(v_proj, v_spacing);
    const long long v_steps = std::llround((v_proj - new_v) / v_spacing);
    int shift_row = 0;
    double new_h;
    if (hexagonal) {
        // Rows an odd number of steps away are offset by half a spacing.
        if (v_steps % 2 != 0)
            h_proj += h_spacing / 2;
        new_h = wrap(h_proj, h_spacing / 2);
        const double steps = std::round((h_proj - new_h) / (h_spacing / 2));
        if (!(std::fabs(steps) < 1e15))
            return;  // a grid this fine has no row parity LFToolbox could use
        shift_row = (std::fmod(std::fabs(steps), 2.0) != 0) ? 1 : 2;
    } else {
        new_h = wrap(h_proj, h_spacing);
    }
    const Vec2 offset{new_h * e.x + new_v * down.x, new_h * e.y + new_v * down.y};

    // The lenslet at (row 1, col 1).
    const double first_shift = shift_row == 1 ? h_spacing / 2 : 0.0;
    const double first_u = offset.x + first_shift * e.x - 1, first_v = offset.y + first_shift * e.y - 1;
    LensIndex first;
    if (!own_lens(m, sensor_point(m, W, H, first_u + 0.5, first_v + 0.5), &first))
        return;
    // As LFBuildLensletGridModel: UMax = floor((W - HOffset) / HSpacing) + 1, likewise VMax;
    // counts beyond 1e15 (absurdly fine grids) are not expressible.
    const double u_max = std::floor((W - offset.x) / h_spacing) + 1;
    const double v_max = std::floor((H - offset.y) / v_spacing) + 1;
    if (!(u_max >= 0 && u_max < 1e15 && v_max >= 0 && v_max < 1e15))
        return;

    lattice->first_lens = first;
    lattice->h_spacing = h_spacing;
    lattice->v_spacing = v_spacing;
    lattice->rot = std::atan2(e.y, e.x);
    lattice->h_offset = offset.x;
    lattice->v_offset = offset.y;
    lattice->first_pos_shift_row = shift_row;
    lattice->u_max = (long long)u_max;
    lattice->v_max = (long long)v_max;
    lattice->lftoolbox_valid = true;
}

} // namespace

Vec3 sensor_point(const Model& m, int W, int H, double pu, double pv)
{
    return Vec3{-(pu - 0.5 * W) * m.pixel_size_mm[0] + m.sensor_offset_mm[0],
                (pv - 0.5 * H) * m.pixel_size_mm[1] + m.sensor_offset_mm[1], m.sensor_z_mm};
}

bool sensor_to_pixel(const Model& m, int W, int H, double x_mm, double y_mm, double* u, double* v)
{
    *u = 0.5 * W - 0.5 - (x_mm - m.sensor_offset_mm[0]) / m.pixel_size_mm[0];
    *v = 0.5 * H - 0.5 + (y_mm - m.sensor_offset_mm[1]) / m.pixel_size_mm[1];
    return *u >= -0.5 && *u < W - 0.5 && *v >= -0.5 && *v < H - 0.5;
}

Vec2 principal_point_px(const Model& m, int W, int H)
{
    Vec2 p;
    sensor_to_pixel(m, W, H, 0, 0, &p.x, &p.y);
    return p;
}

Vec3 lens_centre_mm(const Model& m, LensIndex lens)
{
    const Vec2 c = lens_centre(m.grid, m.pitch_mm, lens);
    return to_optics(m, Vec3{c.x, c.y, 0});
}

bool own_lens(const Model& m, Vec3 p, LensIndex* lens)
{
    Vec2 q;
    if (!project_to_array(m, p, &q))
        return false;
    *lens = nearest_lens(m.grid, m.pitch_mm, q.x, q.y);
    return true;
}

bool generate_ray(const Model& m, int W, int H, int i, int j, const CameraSample& sample, const LensIndex* lens,
                  OpticsRay* out)
{
    const Vec3 p = sensor_point(m, W, H, i + sample.pixel_u, j + sample.pixel_v);
    return trace_sensor_point(m, p, lens, sample.lens_u, sample.lens_v, true, out);
}

int overlap_lenses(const Model& m, int W, int H, int i, int j, LensIndex* out, int capacity)
{
    if (capacity < 1 || m.grid == GridType::None)
        return 0;
    const Vec3 p = sensor_point(m, W, H, i + 0.5, j + 0.5);
    LensIndex own;
    if (!own_lens(m, p, &own))
        return 0;
    out[0] = own;
    int count = 1;
    if (!m.model_overlap)
        return count;
    const int rings = m.overlap_rings;
    const std::int64_t own_skew = skew_k(m.grid, own);
    const bool hexagonal = m.grid == GridType::Hexagonal;
    for (int dl = -rings; dl <= rings; ++dl) {
        for (int dk = -rings; dk <= rings; ++dk) {
            if (dk == 0 && dl == 0)
                continue;
            if (hexagonal && std::abs(dk + dl) > rings)
                continue;  // hexagonal ring distance in skew indices: max(|dk|, |dl|, |dk + dl|)
            const LensIndex lens = from_skew(m.grid, own_skew + dk, own.l + dl);
            if (m.pose.tilt_sine <= kMaxPrunedTiltSine && !lens_reaches_pixel(m, lens, p))
                continue;
            if (count >= capacity)
                return count;
            out[count++] = lens;
        }
    }
    return count;
}

bool chief_ray_through(const Model& m, int W, int H, double pu, double pv, const LensIndex* lens, OpticsRay* out)
{
    return trace_sensor_point(m, sensor_point(m, W, H, pu, pv), lens, 0.5, 0.5, false, out);
}

OpticsRay chief_ray(const Model& m, int W, int H, int i, int j)
{
    OpticsRay ray;
    if (chief_ray_through(m, W, H, i + 0.5, j + 0.5, nullptr, &ray))
        return ray;
    const Vec3 p = sensor_point(m, W, H, i + 0.5, j + 0.5);
    if (!finish(Vec3{0, 0, 0}, -p, &ray))
        finish(Vec3{0, 0, 0}, Vec3{0, 0, 1}, &ray);
    return ray;
}

std::vector<PixelHit> forward_project(const Model& m, int W, int H, const double point_mm[3])
{
    std::vector<PixelHit> hits;
    const Vec3 point{point_mm[0], point_mm[1], point_mm[2]};
    if (!is_finite(point))
        return hits;
    if (m.grid == GridType::None) {
        if (!(point.z > 0))
            return hits;
        // Pinhole, or the chief ray of a thin lens (the centre of its blur disc).
        const double s = m.sensor_z_mm / point.z;
        double u, v;
        if (sensor_to_pixel(m, W, H, point.x * s, point.y * s, &u, &v))
            hits.push_back(PixelHit{LensIndex{0, 0}, u, v});
        return hits;
    }
    if (m.main_lens == MainLensType::None) {
        project_without_main(m, W, H, point, &hits);
        return hits;
    }
    if (!(point.z > 0))
        return hits;
    if (m.main_lens == MainLensType::Pinhole)
        project_through_pinhole_main(m, W, H, point, &hits);
    else
        project_through_thin_main(m, W, H, point, &hits);
    return hits;
}

bool microimage_centre_px(const Model& m, int W, int H, LensIndex lens, double* u, double* v)
{
    Vec2 px;
    if (m.grid == GridType::None || !local_to_px(m, W, H, lens_centre(m.grid, m.pitch_mm, lens), &px))
        return false;
    *u = px.x;
    *v = px.y;
    return true;
}

MicroimageLattice microimage_lattice(const Model& m, int W, int H)
{
    MicroimageLattice lattice = MicroimageLattice();
    lattice.valid = false;
    lattice.lftoolbox_valid = false;
    if (m.grid == GridType::None)
        return lattice;
    Vec2 origin;
    if (!local_to_px(m, W, H, Vec2{0, 0}, &origin))
        return lattice;
    const double p = m.pitch_mm;
    const Vec2 a_local{p, 0};
    const Vec2 b_local = m.grid == GridType::Hexagonal ? Vec2{p / 2, row_spacing(m.grid, p)} : Vec2{0, p};
    // Central differences at the array centre: exact for an affine map, the tangent map otherwise.
    const double step = 1e-3;
    Vec2 basis[2];
    const Vec2 directions[2] = {a_local, b_local};
    for (int i = 0; i < 2; ++i) {
        Vec2 plus, minus;
        if (!local_to_px(m, W, H, step * directions[i], &plus) ||
            !local_to_px(m, W, H, (-step) * directions[i], &minus))
            return lattice;
        basis[i] = (0.5 / step) * (plus - minus);
    }
    lattice.valid = true;
    lattice.origin_px[0] = origin.x;
    lattice.origin_px[1] = origin.y;
    lattice.basis_a_px[0] = basis[0].x;
    lattice.basis_a_px[1] = basis[0].y;
    lattice.basis_b_px[0] = basis[1].x;
    lattice.basis_b_px[1] = basis[1].y;
    // Orthogonal projection (no main lens) of any plane is affine; central projection only of a
    // plane parallel to the sensor.
    lattice.exact = m.main_lens == MainLensType::None || !m.pose.tilted;
    fit_lftoolbox(m, W, H, &lattice);
    return lattice;
}

} // namespace plenoptic
