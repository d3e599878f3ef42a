// SPDX-License-Identifier: AGPL-3.0-or-later
// Forward projection of 3-D points through ideal thin and thick lenses and pinholes, in closed
// form; a traced (prescription) lens goes to projection/traced_projection.cpp.

#include "plenoptic/projection/projection.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "plenoptic/camera/rays.h"
#include "plenoptic/projection/projection_internal.h"
#include "plenoptic/camera/rays_internal.h"
#include "plenoptic/projection/traced_projection.h"

namespace plenoptic {

namespace detail {

bool sensor_hit_through_lens(const PlenopticCamera& m, LensIndex lens, Vec3 h, Vec3 towards_sensor, Vec3* hit)
{
    const ArrayRay bent = m.array.microlens->towards_sensor(m.array, lens, h, towards_sensor);
    if (!bent.passed)
        return false;
    const Vec3 direction = bent.direction;
    if (!(direction.z < 0))
        return false;
    const double travel = (m.sensor.z_mm - bent.origin.z) / direction.z;
    if (!(travel > 0))
        return false;
    *hit = bent.origin + travel * direction;
    return is_finite(*hit);
}

int receiving_rings(const PlenopticCamera& m) { return m.overlap.modelled ? m.overlap.rings : 0; }

bool within_rings(const PlenopticCamera& m, LensIndex a, LensIndex b, int rings)
{
    const std::int64_t dk = skew_k(m.array.grid, a) - skew_k(m.array.grid, b);
    const std::int64_t dl = a.l - b.l;
    std::int64_t d = std::max(dk < 0 ? -dk : dk, dl < 0 ? -dl : dl);
    if (m.array.grid == GridType::Hexagonal)
        d = std::max(d, dk + dl < 0 ? -(dk + dl) : dk + dl);
    return d <= rings;
}

std::vector<Vec2> picture_polygon(const PlenopticCamera& m)
{
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    const Vec3 a = m.sensor.point(0, 0), b = m.sensor.point(W, H);
    return std::vector<Vec2>{Vec2{a.x, a.y}, Vec2{b.x, a.y}, Vec2{b.x, b.y}, Vec2{a.x, b.y}};
}

std::vector<Vec2> microimage_cell(const PlenopticCamera& m, LensIndex lens)
{
    Vec2 cell[6];
    const int count = m.array.cell_corners(cell);
    const Vec2 c = m.array.centre_local(lens);
    std::vector<Vec2> out;
    for (int i = 0; i < count; ++i) {
        const Vec3 q = m.array.to_optics(Vec3{c.x + cell[i].x, c.y + cell[i].y, 0});
        double s = 1;
        if (m.lens) {
            if (!(q.z < 0))
                return std::vector<Vec2>();
            s = m.sensor.z_mm / q.z;
        }
        out.push_back(Vec2{q.x * s, q.y * s});
    }
    return out;
}

bool delivered_point(const PlenopticCamera& m, LensIndex lens, Vec2 s)
{
    if (!m.sensor.to_pixel(s.x, s.y).inside)
        return false;
    const OwnLens owner = own_lens(m, Vec3{s.x, s.y, m.sensor.z_mm});
    return owner.found && within_rings(m, owner.lens, lens, receiving_rings(m));
}

void add_point_hit(const PlenopticCamera& m, LensIndex lens, Vec3 s, double fraction, std::vector<PixelHit>* hits)
{
    if (!delivered_point(m, lens, Vec2{s.x, s.y}))
        return;
    const PixelPoint px = m.sensor.to_pixel(s.x, s.y);
    hits->push_back(PixelHit{lens, px.u, px.v, fraction});
}

} // namespace detail

namespace {

using detail::project_to_array;
using detail::add_point_hit;
using detail::delivered_point;
using detail::microimage_cell;
using detail::picture_polygon;
using detail::receiving_rings;
using detail::sensor_hit_through_lens;
using detail::within_rings;

// Homogeneous point (x, y, z, w): the point (x/w, y/w, z/w), or the direction (x, y, z) if w = 0.
typedef HomogeneousPoint Homogeneous;

// Candidate lenses are enumerated in a box of array-local coordinates.
struct Box {
    bool valid;
    double x0, x1, y0, y1;
};

// Bound on the lenses forward_project examines for one point, so no input can make it hang: about
// 4 million, ten times the lenses of the largest sensors in use, and about a second of work
// (an array tilted almost edge-on to the sensor makes a few pixels see millions of lenses).
const long long kMaxForwardLenses = 1LL << 22;

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

// The smallest box holding the points (not valid when there are none).
Box bounding_box(const std::vector<Vec2>& points)
{
    Box box{false, 0, 0, 0, 0};
    for (const Vec2& q : points)
        include(&box, q);
    return box;
}

// Whether two valid boxes share a point (touching counts).
bool overlap(Box a, Box b)
{
    return !(a.x1 < b.x0 || a.x0 > b.x1 || a.y1 < b.y0 || a.y0 > b.y1);
}

// The part of the array plane whose lenses can image into the picture: the image corners
// projected onto the array, grown by two pitches. Invalid if a corner does not project.
Box sensor_box(const PlenopticCamera& m)
{
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    Box box{false, 0, 0, 0, 0};
    const double corners[4][2] = {{0, 0}, {double(W), 0}, {0, double(H)}, {double(W), double(H)}};
    for (int i = 0; i < 4; ++i) {
        Vec2 q;
        if (!project_to_array(m, m.sensor.point(corners[i][0], corners[i][1]), &q))
            return Box{false, 0, 0, 0, 0};
        include(&box, q);
    }
    return grow(box, 2 * m.array.pitch_mm);
}

// Calls visit(lens) for every lens whose centre lies in the box (array-local), row by row.
template <class Visit>
void for_each_lens_in_box(const PlenopticCamera& m, Box box, Visit visit)
{
    if (!box.valid || !(box.x0 <= box.x1) || !(box.y0 <= box.y1))
        return;
    const double row = m.array.row_spacing_mm();
    const double rows = std::floor(box.y1 / row) - std::ceil(box.y0 / row) + 1;
    const double columns = (box.x1 - box.x0) / m.array.pitch_mm + 2;
    if (!(rows * columns <= double(kMaxForwardLenses)))
        return;  // absurd sizes: give no hits rather than hang
    const double limit = double(kMaxLensIndex);
    if (!(std::fabs(box.y0 / row) < limit && std::fabs(box.y1 / row) < limit &&
          std::fabs(box.x0 / m.array.pitch_mm) < limit && std::fabs(box.x1 / m.array.pitch_mm) < limit))
        return;
    const std::int64_t l0 = std::int64_t(std::ceil(box.y0 / row));
    const std::int64_t l1 = std::int64_t(std::floor(box.y1 / row));
    for (std::int64_t l = l0; l <= l1; ++l) {
        const double shift = (m.array.grid == GridType::Hexagonal && floor_mod(l, 2) == 1) ? 0.5 : 0.0;
        const std::int64_t k0 = std::int64_t(std::ceil(box.x0 / m.array.pitch_mm - shift));
        const std::int64_t k1 = std::int64_t(std::floor(box.x1 / m.array.pitch_mm - shift));
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
// through the lens where it lets light through (its cell; a pinhole's centre only): that part,
// projected from the image point onto the main-lens plane, must meet the aperture disc.
bool lens_sees(const PlenopticCamera& m, Homogeneous image, LensIndex lens)
{
    const Vec3 pupil = m.lens->exit_pupil_centre();
    const Vec2 c = m.array.centre_local(lens);
    const bool whole_cell = m.array.microlens->forms_image();
    Vec2 local[6];
    int count = 1;
    local[0] = Vec2{0, 0};
    if (whole_cell)
        count = m.array.cell_corners(local);
    Vec2 projected[6];
    double first_sign = 0;
    for (int i = 0; i < count; ++i) {
        const Vec3 corner = m.array.to_optics(Vec3{c.x + local[i].x, c.y + local[i].y, 0});
        Homogeneous hit;
        if (!line_meets_plane(image, corner, Vec3{0, 0, 1}, pupil, &hit))
            return whole_cell;  // projection unbounded: keep (conservative)
        const double sign = hit.w > 0 ? 1 : -1;
        if (i == 0)
            first_sign = sign;
        else if (sign != first_sign)
            return true;  // the cell straddles the vanishing line: unbounded, keep
        projected[i] = Vec2{hit.xyz.x / hit.w - pupil.x, hit.xyz.y / hit.w - pupil.y};
    }
    const double radius = m.lens->exit_pupil_radius();
    if (count == 1)
        return dot(projected[0], projected[0]) <= radius * radius;
    return distance_to_origin(projected, count) <= radius;
}

// The cone of light from the main aperture to the point's image X', met with the array plane:
// a polygon of kFootprintSides corners in array-local coordinates. False when the cone does not
// cross the plane as a bounded region.
const int kFootprintSides = 96;

bool cone_footprint(const PlenopticCamera& m, Homogeneous image, Vec2 footprint[kFootprintSides])
{
    const Vec3 pupil = m.lens->exit_pupil_centre();
    const double r = m.lens->exit_pupil_radius();
    double first_sign = 0;
    for (int i = 0; i < kFootprintSides; ++i) {
        const double angle = 2 * kPi * i / kFootprintSides;
        Homogeneous hit;
        if (!line_meets_plane(image, pupil + Vec3{r * std::cos(angle), r * std::sin(angle), 0}, m.array.pose.normal,
                              m.array.pose.centre_mm, &hit))
            return false;
        const double sign = hit.w > 0 ? 1 : -1;
        if (i == 0)
            first_sign = sign;
        else if (sign != first_sign)
            return false;
        const Vec3 local = m.array.to_local((1 / hit.w) * hit.xyz);
        footprint[i] = Vec2{local.x, local.y};
    }
    return true;
}

// Twice the signed area of a polygon (positive counter-clockwise).
double signed_area2(const std::vector<Vec2>& poly)
{
    double area2 = 0;
    for (size_t i = 0; i < poly.size(); ++i)
        area2 += cross(poly[i], poly[(i + 1) % poly.size()]);
    return area2;
}

// The convex polygon `subject` clipped by the convex polygon `clip` (Sutherland-Hodgman); both in
// either orientation.
std::vector<Vec2> clip_polygon(std::vector<Vec2> poly, std::vector<Vec2> clip)
{
    if (signed_area2(poly) < 0)
        std::reverse(poly.begin(), poly.end());
    if (signed_area2(clip) < 0)
        std::reverse(clip.begin(), clip.end());
    std::vector<Vec2> next;
    for (size_t e = 0; e < clip.size() && !poly.empty(); ++e) {
        const Vec2 a = clip[e], b = clip[(e + 1) % clip.size()];
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
    return poly;
}

// Area (>= 0) and centroid of a simple polygon; area 0 (centroid untouched) when degenerate.
double area_centroid(const std::vector<Vec2>& poly, Vec2* centroid)
{
    if (poly.size() < 3)
        return 0;
    // About the first corner, so that far-off polygons keep their precision.
    const Vec2 o = poly[0];
    double area = 0, cx = 0, cy = 0;
    for (size_t i = 0; i < poly.size(); ++i) {
        const Vec2 p = poly[i] - o, q = poly[(i + 1) % poly.size()] - o;
        const double w = cross(p, q);
        area += w;
        cx += (p.x + q.x) * w;
        cy += (p.y + q.y) * w;
    }
    if (!(std::fabs(area) > 0) || !std::isfinite(area))
        return 0;
    const Vec2 c{o.x + cx / (3 * area), o.y + cy / (3 * area)};
    if (!is_finite(c))
        return 0;
    *centroid = c;
    return 0.5 * std::fabs(area);
}

// The part of `light` (a convex polygon on the sensor plane, x, y, mm, uniformly lit) that the
// renderer delivers through `lens`: inside the picture and inside the microimage cells of the
// lenses within the receiving rings. Returns its area and centroid.
double delivered_area(const PlenopticCamera& m, LensIndex lens, const std::vector<Vec2>& light, Vec2* centroid)
{
    const std::vector<Vec2> inside = clip_polygon(light, picture_polygon(m));
    if (inside.size() < 3)
        return 0;
    const Box lit = bounding_box(inside);
    const double x0 = lit.x0, x1 = lit.x1, y0 = lit.y0, y1 = lit.y1;
    const int rings = receiving_rings(m);
    if (!m.array.pose.tilted && m.lens) {
        // Fast path: the cells within `rings` rings cover the disc of radius rings * row spacing
        // about the lens centre (ring r lies at least r row spacings away, and a point that far
        // is nearer to a lens within the rings than to any beyond), or the cell's inscribed
        // circle without overlap; an untilted array maps to the sensor by one scale factor.
        const Vec3 c = lens_centre_mm(m, lens);
        if (c.z < 0) {
            const double scale = m.sensor.z_mm / c.z;
            const double radius = scale * (rings > 0 ? rings * m.array.row_spacing_mm() : m.array.cell_inradius_mm);
            bool covered = true;
            for (const Vec2& q : inside)
                covered = covered && length(q - Vec2{c.x * scale, c.y * scale}) <= radius * (1 - 1e-9);
            if (covered)
                return area_centroid(inside, centroid);
        }
    }
    const std::int64_t k0 = skew_k(m.array.grid, lens);
    double area = 0, cx = 0, cy = 0;
    for (int dl = -rings; dl <= rings; ++dl) {
        for (int dk = -rings; dk <= rings; ++dk) {
            const LensIndex other = from_skew(m.array.grid, k0 + dk, lens.l + dl);
            if (!within_rings(m, other, lens, rings))
                continue;
            if (!m.array.pose.tilted && m.lens) {
                // Cheap rejection: the cell's circumscribed circle, scaled onto the sensor.
                const Vec3 oc = lens_centre_mm(m, other);
                if (oc.z < 0) {
                    const double scale = m.sensor.z_mm / oc.z;
                    const double reach = scale * m.array.cell_circumradius_mm;
                    const double ox = oc.x * scale, oy = oc.y * scale;
                    if (ox + reach < x0 || ox - reach > x1 || oy + reach < y0 || oy - reach > y1)
                        continue;
                }
            }
            const std::vector<Vec2> cell = microimage_cell(m, other);
            if (cell.empty())
                continue;
            if (!overlap(bounding_box(cell), lit))
                continue;
            Vec2 c;
            const double a = area_centroid(clip_polygon(inside, cell), &c);
            if (a > 0) {
                area += a;
                cx += a * c.x;
                cy += a * c.y;
            }
        }
    }
    if (!(area > 0))
        return 0;
    *centroid = Vec2{cx / area, cy / area};
    return is_finite(*centroid) ? area : 0;
}

// Adds the image of the light `light` (sensor plane, uniformly lit, carrying `fraction` of the
// point's light) through `lens`: the centroid of the part the renderer delivers, with the fraction
// scaled to that part. A spot smaller than a thousandth of a pixel is a point.
void add_spot_hit(const PlenopticCamera& m, LensIndex lens, const std::vector<Vec2>& light, double fraction,
                  std::vector<PixelHit>* hits)
{
    Vec2 centre{0, 0};
    const double area = area_centroid(light, &centre);
    const double tiny = 1e-6 * m.sensor.pixel_size_mm[0] * m.sensor.pixel_size_mm[1];
    if (!(area > tiny)) {
        if (light.empty())
            return;
        Vec2 mean{0, 0};
        for (const Vec2& q : light)
            mean = mean + q;
        mean = (1.0 / light.size()) * mean;
        add_point_hit(m, lens, Vec3{mean.x, mean.y, m.sensor.z_mm}, fraction, hits);
        return;
    }
    Vec2 centroid;
    const double kept = delivered_area(m, lens, light, &centroid);
    if (!(kept > 0))
        return;
    const PixelPoint px = m.sensor.to_pixel(centroid.x, centroid.y);
    if (!px.inside)
        return;  // only by rounding, for light along the picture's edge
    hits->push_back(PixelHit{lens, px.u, px.v, fraction * std::min(1.0, kept / area)});
}

// Light of the point whose image is X' through a lens whose trace is not first-order (a
// refracting microlens): the cone's footprint within the lens's cell grown by the glass's
// thickness (light crossing the array's plane there may still enter and leave this lens), sampled
// on a grid of kTracedGrid a side over the box of what a coarser grid finds passing; each sample's
// light from X' through the
// lens, traced to the sensor. The image is the centroid of the hits the renderer delivers
// (delivered_point: in the lens's own microimage cell, or a cell within the overlap rings, and in
// the picture), their share of the cone's footprint its fraction. Light that meets a cap near its
// rim (or goes on through a neighbour's glass and cap) lands far from the rest, from thin bands
// of the cell that a regular grid samples by chance: a grid step whose sample's light is delivered
// and a neighbour's is not, or lands more than kTracedJumpPx pixels from it, is sampled again on
// kTracedRefine x kTracedRefine points (caps facing the sensor, 96 a side alone: the centroid
// 0.4 px from a converged trace; refined: 0.02 px).
const int kTracedCoarseGrid = 24, kTracedGrid = 96, kTracedRefine = 8;
const double kTracedJumpPx = 3;

void project_through_traced_lens(const PlenopticCamera& m, Homogeneous image, LensIndex lens,
                                 const std::vector<Vec2>& cone_polygon, double cone_area, std::vector<PixelHit>* hits)
{
    Vec2 cell[6];
    const int count = m.array.cell_corners(cell);
    const Vec2 c = m.array.centre_local(lens);
    const double grow = 1 + m.array.microlens->thickness_mm() / m.array.cell_inradius_mm;
    std::vector<Vec2> corners(count);
    for (int i = 0; i < count; ++i)
        corners[i] = c + grow * cell[i];
    const std::vector<Vec2> part = clip_polygon(cone_polygon, corners);
    if (part.size() < 3)
        return;
    // A coarse grid over the part finds the box of the samples that pass; the fine grid covers that
    // box (grown by a coarse step), where the light through the lens lies.
    const Box outer = bounding_box(part);
    auto sample = [&](const Box& region, int grid, const std::function<void(Vec2, Vec3)>& use) {
        const double dx = (region.x1 - region.x0) / grid, dy = (region.y1 - region.y0) / grid;
        for (int j = 0; j < grid; ++j) {
            for (int i = 0; i < grid; ++i) {
                const Vec2 q{region.x0 + (i + 0.5) * dx, region.y0 + (j + 0.5) * dy};
                bool inside = true;  // the part is convex (a convex cone's footprint clipped by a convex cell)
                for (size_t k = 0; k < part.size() && inside; ++k)
                    inside = cross(part[(k + 1) % part.size()] - part[k], q - part[k]) >= 0;
                if (!inside)
                    continue;
                const Vec3 h = m.array.to_optics(Vec3{q.x, q.y, 0});
                Vec3 towards = image.w == 0 ? image.xyz : (1 / image.w) * image.xyz - h;
                if (dot(towards, m.array.pose.normal) > 0)
                    towards = -towards;
                Vec3 hit;
                if (sensor_hit_through_lens(m, lens, h, towards, &hit) && delivered_point(m, lens, Vec2{hit.x, hit.y}))
                    use(q, hit);
            }
        }
    };
    const double coarse_x = (outer.x1 - outer.x0) / kTracedCoarseGrid, coarse_y = (outer.y1 - outer.y0) / kTracedCoarseGrid;
    if (!(coarse_x > 0) || !(coarse_y > 0))
        return;
    Box found{true, INFINITY, -INFINITY, INFINITY, -INFINITY};
    sample(outer, kTracedCoarseGrid, [&](Vec2 q, Vec3) {
        found.x0 = std::min(found.x0, q.x);
        found.x1 = std::max(found.x1, q.x);
        found.y0 = std::min(found.y0, q.y);
        found.y1 = std::max(found.y1, q.y);
    });
    if (!(found.x1 >= found.x0))
        return;
    const Box region{true, std::max(outer.x0, found.x0 - coarse_x), std::min(outer.x1, found.x1 + coarse_x),
                     std::max(outer.y0, found.y0 - coarse_y), std::min(outer.y1, found.y1 + coarse_y)};
    const double dx = (region.x1 - region.x0) / kTracedGrid, dy = (region.y1 - region.y0) / kTracedGrid;
    // The fine grid's delivered hits, then the steps to sample again (those at a jump).
    const int n = kTracedGrid;
    std::vector<char> kept(std::size_t(n) * n, 0), again(std::size_t(n) * n, 0);
    std::vector<Vec2> at(std::size_t(n) * n);
    sample(region, n, [&](Vec2 q, Vec3 hit) {
        const int i = std::min(n - 1, std::max(0, int(std::floor((q.x - region.x0) / dx)))),
                  j = std::min(n - 1, std::max(0, int(std::floor((q.y - region.y0) / dy))));
        kept[std::size_t(j) * n + i] = 1;
        at[std::size_t(j) * n + i] = Vec2{hit.x, hit.y};
    });
    const double jump = kTracedJumpPx * std::max(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1]);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const std::size_t a = std::size_t(j) * n + i;
            const std::size_t next[2] = {i + 1 < n ? a + 1 : a, j + 1 < n ? a + n : a};
            for (std::size_t b : next) {
                if (b == a)
                    continue;
                if (kept[a] != kept[b] || (kept[a] && length(at[a] - at[b]) > jump))
                    again[a] = again[b] = 1;
            }
        }
    }
    double passed = 0, sx = 0, sy = 0;
    for (std::size_t a = 0; a < kept.size(); ++a) {
        if (kept[a] && !again[a]) {
            passed += 1;
            sx += at[a].x;
            sy += at[a].y;
        }
    }
    const double weight = 1.0 / (kTracedRefine * kTracedRefine);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            if (!again[std::size_t(j) * n + i])
                continue;
            const Box step{true, region.x0 + i * dx, region.x0 + (i + 1) * dx, region.y0 + j * dy, region.y0 + (j + 1) * dy};
            sample(step, kTracedRefine, [&](Vec2, Vec3 hit) {
                passed += weight;
                sx += weight * hit.x;
                sy += weight * hit.y;
            });
        }
    }
    if (!(passed > 0))
        return;
    const double fraction = std::min(1.0, passed * dx * dy / cone_area);
    add_point_hit(m, lens, Vec3{sx / passed, sy / passed, m.sensor.z_mm}, fraction, hits);
}

// The picture on the sensor plane (x, y, mm), as a box.
Box picture_box(const PlenopticCamera& m) { return bounding_box(picture_polygon(m)); }

// Whether light through `lens` from a part of its cell (array-local corners) towards the sensor,
// along lines from the image point, can land in the picture: false only when the bounding box of
// the cell's corners carried to the sensor misses it (true when a corner cannot be carried).
bool cell_spot_may_reach_picture(const PlenopticCamera& m, LensIndex lens, Homogeneous image,
                                 const std::vector<Vec2>& corners, Box picture)
{
    Box spot{false, 0, 0, 0, 0};
    for (const Vec2& q : corners) {
        const Vec3 h = m.array.to_optics(Vec3{q.x, q.y, 0});
        Vec3 towards = image.w == 0 ? image.xyz : (1 / image.w) * image.xyz - h;
        if (dot(towards, m.array.pose.normal) > 0)
            towards = -towards;
        Vec3 hit;
        if (!sensor_hit_through_lens(m, lens, h, towards, &hit) || !is_finite(hit))
            return true;
        include(&spot, Vec2{hit.x, hit.y});
    }
    return !spot.valid || !picture.valid || overlap(spot, picture);
}

void project_through_thin_main(const PlenopticCamera& m, Vec3 point, std::vector<PixelHit>* hits)
{
    const Homogeneous image = m.lens->paraxial_image(point);
    const Vec3 pupil = m.lens->exit_pupil_centre();
    const Vec3 n = m.array.pose.normal;
    const Vec3 centre = m.array.pose.centre_mm;

    // Footprint of the cone (main aperture -> image) on the array: project the aperture's
    // bounding square from the image point; bounded when all four corners project to one side.
    Box footprint{false, 0, 0, 0, 0};
    const double r = m.lens->exit_pupil_radius();
    const double square[4][2] = {{-r, -r}, {r, -r}, {r, r}, {-r, r}};
    double first_sign = 0;
    bool bounded = true;
    for (int i = 0; i < 4 && bounded; ++i) {
        Homogeneous hit;
        if (!line_meets_plane(image, pupil + Vec3{square[i][0], square[i][1], 0}, n, centre, &hit)) {
            bounded = false;
            break;
        }
        const double sign = hit.w > 0 ? 1 : -1;
        if (i == 0)
            first_sign = sign;
        bounded = sign == first_sign;
        const Vec3 local = m.array.to_local((1 / hit.w) * hit.xyz);
        include(&footprint, Vec2{local.x, local.y});
    }
    if (!bounded)
        footprint.valid = false;
    else
        footprint = grow(footprint, m.array.cell_circumradius_mm);
    // With overlap modelling, light through a lens reaches the microimages of lenses up to
    // overlap_rings rings away (each ring at most a pitch further).
    const Box box = intersect(footprint, grow(sensor_box(m), receiving_rings(m) * m.array.pitch_mm));
    if (!box.valid)
        return;

    // Is the image point on the array plane? Then the chief line through a lens centre runs in
    // the plane and the lens containing X' images the point along the main-lens chief ray.
    const double offset = dot(n, image.xyz) - image.w * dot(n, centre);
    const bool on_array = std::fabs(offset) <= 1e-12 * (std::fabs(dot(n, image.xyz)) + std::fabs(image.w * dot(n, centre)));

    if (on_array) {
        // The cone's footprint is the single point X' = h: only the lens containing it sees the
        // point. A pinhole images it along the main-lens chief ray O -> h; a thin microlens
        // spreads the cone (every direction from the main aperture to h) over a spot, the image
        // of the aperture through h, whose delivered part's centroid is the image.
        if (image.w == 0)
            return;
        const Vec3 h = (1 / image.w) * image.xyz;
        const Vec3 h_local = m.array.to_local(h);
        const LensIndex lens = m.array.nearest(h_local.x, h_local.y);
        if (!m.array.microlens->forms_image()) {
            if (length(h - lens_centre_mm(m, lens)) > 1e-9 * m.array.pitch_mm)
                return;  // a pinhole passes light only at its centre
            Vec3 hit;
            if (sensor_hit_through_lens(m, lens, h, h - pupil, &hit))
                add_point_hit(m, lens, hit, 1.0, hits);
            return;
        }
        std::vector<Vec2> spot;
        for (int i = 0; i < kFootprintSides; ++i) {
            const double angle = 2 * kPi * i / kFootprintSides;
            const Vec3 on_aperture = pupil + Vec3{r * std::cos(angle), r * std::sin(angle), 0};
            Vec3 hit;
            if (!sensor_hit_through_lens(m, lens, h, h - on_aperture, &hit))
                return;
            spot.push_back(Vec2{hit.x, hit.y});
        }
        add_spot_hit(m, lens, spot, 1.0, hits);
        return;
    }

    // Thin microlenses: the point's light through a lens is the part of the cone's footprint
    // inside that lens's cell; it lands on the sensor as that part mapped through the lens (the
    // map from array to sensor is affine, so uniform light stays uniform and centroids map to
    // centroids), and the image is the centroid of what the renderer delivers of it: inside the
    // picture, and inside that lens's own microimage cell or, where overlap is modelled, the cells
    // of the lenses within overlap_rings rings (delivered_area). A whole cell well inside its
    // microimage gives the Institut Pascal line through the lens centre; plenoptic 1.0 cameras,
    // whose footprints are small, need the partial cells. The fraction is the part of the point's
    // light through the main aperture that arrives in that image.
    Vec2 cone[kFootprintSides];
    const bool thin_microlenses = m.array.microlens->forms_image();
    const bool use_footprint = thin_microlenses && cone_footprint(m, image, cone);
    Vec2 cell[6];
    const int cell_count = thin_microlenses ? m.array.cell_corners(cell) : 0;
    const std::vector<Vec2> cone_polygon(cone, cone + (use_footprint ? kFootprintSides : 0));
    Vec2 unused;
    const double cone_area = use_footprint ? area_centroid(cone_polygon, &unused) : 0;

    const Box picture = picture_box(m);
    const bool traced_microlenses = thin_microlenses && !m.array.microlens->first_order_exact();
    for_each_lens_in_box(m, box, [&](LensIndex lens) {
        if (traced_microlenses) {
            // Refracting microlenses: not affine, and their light crosses the array's plane up
            // to the glass's thickness outside their cell, so the cone's footprint near the cell is
            // sampled and each sample's light traced (the lens decides whether it passes).
            if (use_footprint && cone_area > 0)
                project_through_traced_lens(m, image, lens, cone_polygon, cone_area, hits);
            return;
        }
        if (!lens_sees(m, image, lens))
            return;
        if (use_footprint && cone_area > 0) {
            const Vec2 c = m.array.centre_local(lens);
            std::vector<Vec2> corners(cell_count);
            for (int i = 0; i < cell_count; ++i)
                corners[i] = c + cell[i];
            // Cheap rejection before clipping: the map from array to sensor is affine, so the
            // spot of any part of the cell lies in the bounding box of the cell's mapped corners;
            // a box off the picture delivers nothing (this keeps arrays tilted almost edge-on,
            // where millions of lenses are candidates, to a fraction of a second).
            if (!cell_spot_may_reach_picture(m, lens, image, corners, picture))
                return;
            const std::vector<Vec2> part = clip_polygon(cone_polygon, corners);
            Vec2 centroid{0, 0};
            const double part_area = area_centroid(part, &centroid);
            if (!(part_area > 0))
                return;
            // Each corner of the part, carried to the sensor along the light through it (the line
            // X' - h, towards the sensor).
            std::vector<Vec2> spot;
            for (const Vec2& q : part) {
                const Vec3 h = m.array.to_optics(Vec3{q.x, q.y, 0});
                Vec3 towards = image.w == 0 ? image.xyz : (1 / image.w) * image.xyz - h;
                if (dot(towards, m.array.pose.normal) > 0)
                    towards = -towards;
                Vec3 hit;
                if (!sensor_hit_through_lens(m, lens, h, towards, &hit))
                    return;
                spot.push_back(Vec2{hit.x, hit.y});
            }
            add_spot_hit(m, lens, spot, std::min(1.0, part_area / cone_area), hits);
            return;
        }
        // Pinhole microlenses (or a cone that does not cross the array as a bounded region): the
        // line from X' through the lens centre (its chief ray), met with the sensor plane.
        Homogeneous meet;
        if (!line_meets_plane(image, lens_centre_mm(m, lens), Vec3{0, 0, 1}, Vec3{0, 0, m.sensor.z_mm}, &meet))
            return;
        const Vec3 hit = (1 / meet.w) * meet.xyz;
        if (is_finite(hit))
            add_point_hit(m, lens, hit, 1.0, hits);
    });
}

void project_through_pinhole_main(const PlenopticCamera& m, Vec3 point, std::vector<PixelHit>* hits)
{
    if (!m.array.microlens->forms_image())
        return;  // a pinhole's only ray through the main pinhole misses the point but by chance
    // The single ray: point -> pinhole -> array.
    const Vec3 towards_sensor = -point;
    const double along = dot(m.array.pose.normal, towards_sensor);
    const double t = dot(m.array.pose.normal, m.array.pose.centre_mm) / along;
    if (!(t > 0) || !std::isfinite(t))
        return;
    const Vec3 h = t * towards_sensor;
    const Vec3 h_local = m.array.to_local(h);
    const LensIndex lens = m.array.nearest(h_local.x, h_local.y);
    Vec3 hit;
    if (sensor_hit_through_lens(m, lens, h, towards_sensor, &hit))
        add_point_hit(m, lens, hit, 1.0, hits);
}

void project_without_main(const PlenopticCamera& m, Vec3 point, std::vector<PixelHit>* hits)
{
    const Vec3 local = m.array.to_local(point);
    if (!(local.z > 0))
        return;  // behind the array
    Box box = sensor_box(m);
    if (!m.array.pose.tilted) {
        // A lens images the point into its own cell only if the point is within
        // R (z + d) / d of the lens centre, sideways.
        const double reach = m.array.cell_circumradius_mm * (local.z / effective_array_distance_mm(m) + 1) +
                             m.array.cell_circumradius_mm;
        box = intersect(box, Box{true, local.x - reach, local.x + reach, local.y - reach, local.y + reach});
    }
    for_each_lens_in_box(m, box, [&](LensIndex lens) {
        const Vec3 c = lens_centre_mm(m, lens);
        Vec3 hit;
        if (sensor_hit_through_lens(m, lens, c, c - point, &hit))
            add_point_hit(m, lens, hit, 1.0, hits);
    });
}

} // namespace

std::vector<PixelHit> forward_project(const PlenopticCamera& m, Vec3 point)
{
    std::vector<PixelHit> hits;
    if (!is_finite(point))
        return hits;
    if ((m.lens && m.lens->traced()) || m.distortion())
        return forward_project_traced(m, point, default_traced_projection_options());
    if (m.array.grid == GridType::None) {
        if (!(point.z > 0))
            return hits;
        // Pinhole, or the chief ray of a thin lens (the centre of its blur disc).
        const double s = m.sensor.z_mm / point.z;
        const PixelPoint px = m.sensor.to_pixel(point.x * s, point.y * s);
        if (px.inside)
            hits.push_back(PixelHit{LensIndex{0, 0}, px.u, px.v, 1.0});
        return hits;
    }
    if (!m.lens) {
        project_without_main(m, point, &hits);
        return hits;
    }
    if (!(point.z > 0))
        return hits;
    if (!m.lens->forms_image())
        project_through_pinhole_main(m, point, &hits);
    else
        project_through_thin_main(m, point, &hits);
    return hits;
}

std::vector<PixelHit> PlenopticCamera::project(Vec3 point_mm) const
{
    return forward_project(*this, point_mm);
}

} // namespace plenoptic
