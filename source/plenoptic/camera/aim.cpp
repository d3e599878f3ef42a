// SPDX-License-Identifier: AGPL-3.0-or-later
// Samples where light passes (see the header).

#include "plenoptic/camera/aim.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>
#include <vector>

#include "plenoptic/array/microlens_array.h"
#include "plenoptic/camera/camera_key.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/core/convex_hull.h"
#include "plenoptic/camera/rays_internal.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/pupil_bounds.h"

namespace plenoptic {

namespace {

// Relative widening of every region: its centre and radius come from sums of terms whose rounding
// is ~1e-16 of them, so widened by 1e-12 of them it still holds what the exact one holds. (1e-9,
// as first written, left a band that held 2e-5 of a rim pixel's aimed samples where a microimage's
// rim cuts a sliver of a 0.5 mm cell: the cell disc's radius there is ~6 mm.)
const double kRoundingMargin = 1e-12;
const double kSqrt3 = 1.7320508075688772935;

// An ellipse of a plane (coordinates h): its points centre + z.x g0 + z.y g1, |z| <= 1; its
// semi-axes.
struct PlaneEllipse {
    Vec2 centre, g0, g1;
    double major, minor;
};

// The points h of a plane where |u(h)| <= rho alpha(h), u(h) = u0 + h.x ux + h.y uy a vector normal to
// N (unit) and alpha(h) = alpha0 + alpha.h > 0: where the line from an apex through the point meets
// a disc (centre M, radius rho, normal N), u and alpha being the affine parts of that condition
// times N.(the line's direction). In coordinates y of the plane normal to N (u = u0 + Y h), alpha is
// affine in y, delta0 + delta.y, so |y| <= rho (delta0 + delta.y): an ellipse with a focus at y = 0,
// semi-latus rectum l = rho delta0, eccentricity e = rho |delta|, semi-axes l / (1 - e^2) and
// l / sqrt(1 - e^2), its centre l e / (1 - e^2) from the focus along delta. False when that is not
// a bounded ellipse (e >= 0.5 is refused: no such geometry here) or not finite.
bool focus_ellipse(Vec3 u0, Vec3 ux, Vec3 uy, Vec3 N, double alpha0, Vec2 alpha, double rho, PlaneEllipse* out)
{
    const Vec3 e1 = normalized(Vec3{1, 0, 0} - N.x * N);
    const Vec3 e2 = cross(N, e1);
    const Vec2 y0{dot(e1, u0), dot(e2, u0)};
    const double Y00 = dot(e1, ux), Y01 = dot(e1, uy), Y10 = dot(e2, ux), Y11 = dot(e2, uy);
    const double det = Y00 * Y11 - Y01 * Y10;
    if (!(std::fabs(det) > 0) || !std::isfinite(det))
        return false;
    const auto Yinv = [&](Vec2 v) { return Vec2{(Y11 * v.x - Y01 * v.y) / det, (-Y10 * v.x + Y00 * v.y) / det}; };
    // alpha0 + alpha.h with h = Y^-1 (y - y0): delta = Y^-T alpha, delta0 = alpha0 - alpha.Y^-1 y0.
    const Vec2 delta{(Y11 * alpha.x - Y10 * alpha.y) / det, (-Y01 * alpha.x + Y00 * alpha.y) / det};
    const double delta0 = alpha0 - dot(alpha, Yinv(y0));
    const double l = rho * delta0;
    const Vec2 b = rho * delta;
    const double e = length(b);
    if (!(l > 0) || !(e < 0.5))
        return false;
    const double A = l / (1 - e * e), B = l / std::sqrt(1 - e * e);
    const Vec2 along = e > 0 ? (1 / e) * b : Vec2{1, 0};
    const Vec2 across{-along.y, along.x};
    out->centre = Yinv(A * b - y0);
    out->g0 = Yinv(A * along);
    out->g1 = Yinv(B * across);
    // The semi-axes in h: G's singular values.
    const double Gdet = out->g0.x * out->g1.y - out->g1.x * out->g0.y;
    const double p = dot(out->g0, out->g0), q = dot(out->g0, out->g1), r = dot(out->g1, out->g1);
    const double root = std::sqrt(std::max(0.0, 0.25 * (p - r) * (p - r) + q * q));
    out->major = std::sqrt(0.5 * (p + r) + root);
    out->minor = std::fabs(Gdet) / out->major;
    return out->minor > 0 && std::isfinite(out->major) && is_finite(out->centre);
}

} // namespace

bool camera_can_aim(const PlenopticCamera& m)
{
    // The unbent light of a clear gap (fill_factor) leaves the thin lens's affine map; a mask would
    // only block more, but is kept with the gap for simplicity. A tilted array's cells are not
    // parallel to the sensor (a lens tilted by its errors is aimed in its own frame: lens_aim).
    return m.lens && m.lens->forms_image() && m.array.grid != GridType::None && m.array.microlens &&
           m.array.microlens->aims() && !m.array.pose.tilted && !(m.array.fill_factor < 1) &&
           m.sampling.samples_max > 1;
}

bool lens_aim(const PlenopticCamera& m, LensIndex lens, LensAim* out)
{
    const LensFrame frame = m.array.frame(lens);
    const Vec3 centre = m.array.to_optics(frame.centre);
    const double circumradius = m.array.cell_circumradius_mm;
    // A tilted lens's cell leaves the plane through its centre parallel to the array by up to this.
    const double sin_tilt = frame.tilted ? std::hypot(frame.axes.m[0][2], frame.axes.m[1][2]) : 0;
    const double tilt_rise = circumradius * sin_tilt;
    PupilDisc disc;
    if (m.pupil_bounds) {
        // The bounds are for points q of their plane. A ray from a cell point off it, in the air
        // behind the lens, passes exactly when the ray along the same line from where that line
        // crosses the plane does (PupilBounds::may_pass); every passing ray crosses the exit
        // pupil's plane within reach_mm of the axis, so its slope is at most (the point's distance
        // from the axis + reach) / (its distance to that plane), and the crossing lies within
        // (how far the point is off the plane) times that of the point.
        double radius = circumradius;
        const double off = std::fabs(centre.z - m.pupil_bounds->plane_z()) + tilt_rise;
        if (off > 1e-12 * (1 + std::fabs(centre.z))) {
            const double run = m.lens->exit_pupil_centre().z - centre.z - tilt_rise;
            const double slope = (std::hypot(centre.x, centre.y) + circumradius + m.pupil_bounds->reach_mm()) / run;
            if (!(run > 0) || !std::isfinite(slope))
                return false;
            radius += off * slope * (1 + 1e-9) + 1e-12 * (1 + std::fabs(centre.z));
        }
        PupilDisc discs[PupilBounds::kMaxDiscs];
        const int count = m.pupil_bounds->discs_holding(centre, radius, discs);
        disc = discs[0];
        out->cuts = count - 1;
        for (int k = 0; k < out->cuts; ++k) {
            const Vec3 q = m.array.to_local(discs[k + 1].centre);
            out->cut_m[k] = Vec2{q.x, q.y};
            out->cut_rho[k] = discs[k + 1].radius;
            if (!(is_finite(out->cut_m[k]) && out->cut_rho[k] >= 0 && std::isfinite(out->cut_rho[k])))
                return false;
        }
    } else if (m.lens->traced()) {
        return false;
    } else {
        // An ideal lens blocks exactly outside its exit pupil (the thin lens's aperture in its plane).
        disc = PupilDisc{m.lens->exit_pupil_centre(), m.lens->exit_pupil_radius()};
        out->cuts = 0;
    }
    const Vec3 c = m.array.to_local(centre);
    const Vec3 d = m.array.to_local(disc.centre);
    out->lens = lens;
    out->c = Vec2{c.x, c.y};
    out->z = c.z;
    out->f = frame.focal_mm;
    out->grid = m.array.grid;
    out->pitch = m.array.pitch_mm;
    out->circumradius = circumradius;
    out->Z = d.z - c.z;
    out->m = Vec2{d.x, d.y};
    out->rho = disc.radius;
    out->tilted = frame.tilted;
    out->axes = frame.axes;
    out->sin_tilt = sin_tilt;
    if (!(out->Z > 0 && std::isfinite(out->Z) && out->f != 0 && std::isfinite(out->f) && out->rho >= 0 &&
          std::isfinite(out->rho) && is_finite(out->m) && is_finite(out->c)))
        return false;
    for (int k = 0; k <= LensAim::kMaxCuts; ++k)
        out->seg[k] = Vec2{0, 0};
    if (!frame.tilted)
        return true;
    // In the lens's frame the discs of the array's plane Z in front are tilted by t. A ray from
    // cell point P meets disc k at Q and the lens frame's plane z = Z' through the main disc's
    // centre at Q Z'/Q_z + P (1 - Z'/Q_z): within the disc's shadow from the lens's centre on that
    // plane (the cone from the centre over the disc, cut by the plane: an ellipse, focus_ellipse
    // with u = X (N.M) - M (N.X), alpha = N.X for X = (x, y, Z')), widened by the parallax
    // |P| |1 - Z'/Q_z| <= circumradius (|M_z - Z'| + rho sin t) / (Z' - that). Each flattened disc
    // is the disc about the shadow's centre of radius its semi-major axis and that parallax.
    const Vec3 c3{c.x, c.y, c.z};
    const Vec3 N{frame.axes.m[2][0], frame.axes.m[2][1], frame.axes.m[2][2]};
    out->disc_normal = N;
    out->disc_centre[0] = mul_transposed(frame.axes, Vec3{out->m.x, out->m.y, d.z} - c3);
    out->disc_radius[0] = out->rho;
    for (int k = 0; k < out->cuts; ++k) {
        out->disc_centre[k + 1] = mul_transposed(frame.axes, Vec3{out->cut_m[k].x, out->cut_m[k].y, d.z} - c3);
        out->disc_radius[k + 1] = out->cut_rho[k];
    }
    const double plane = out->disc_centre[0].z;
    for (int k = 0; k <= out->cuts; ++k) {
        const Vec3 M = out->disc_centre[k];
        const double rho = out->disc_radius[k];
        const double NM = dot(N, M);
        const Vec3 u0 = Vec3{0, 0, plane * NM} - (N.z * plane) * M;
        const Vec3 ux = Vec3{NM, 0, 0} - N.x * M, uy = Vec3{0, NM, 0} - N.y * M;
        PlaneEllipse shadow;
        if (!focus_ellipse(u0, ux, uy, N, N.z * plane, Vec2{N.x, N.y}, rho, &shadow))
            return false;
        const double rise = std::fabs(M.z - plane) + rho * sin_tilt;
        const double parallax = circumradius * rise / (plane - rise);
        if (!(plane - rise > 0))
            return false;
        const Vec2 centre{c.x + shadow.centre.x, c.y + shadow.centre.y};
        const double slack = 1e-12 * (std::fabs(centre.x) + std::fabs(centre.y) + plane + rho);
        const double radius = (shadow.major + parallax) * (1 + 1e-10) + slack;
        // The stadium: a point (a cos s, b sin s) of an ellipse with semi-axes a >= b lies within b
        // of the segment of half-length a - b along its major axis (beyond the segment's end its
        // distance to the end is at most b, since (a cos s - (a - b))^2 <= b^2 cos^2 s there). The
        // axis comes from G G^T's larger eigenvalue; its direction's rounding, some 1e-16 a^2 /
        // (a^2 - b^2), moves the ellipse's points by that times a, which 1e-6 (a - b) holds when
        // a - b exceeds 1e-5 a (below that the disc is kept). Behind a traced lens the disc is kept
        // too: there the pupil bounds' own margins lose more samples than the stadium would save
        // (BENCHMARKS.md, "Arrays with manufacturing errors": 0.1 to 0.2 points of the lit pixels'
        // samples for 4.5 % more instructions a pixel, its pixel plans' regions having two corners
        // more and their x ranges' ends more often to be searched).
        const double semi = shadow.major - shadow.minor;
        out->seg_rho[k] = radius;  // (seg[k] is zero from above)
        if (!m.pupil_bounds && semi > 1e-5 * shadow.major) {
            const Vec2 g0 = shadow.g0, g1 = shadow.g1;
            const double a11 = g0.x * g0.x + g1.x * g1.x, a12 = g0.x * g0.y + g1.x * g1.y,
                         a22 = g0.y * g0.y + g1.y * g1.y;
            const double top = 0.5 * (a11 + a22) + std::sqrt(0.25 * (a11 - a22) * (a11 - a22) + a12 * a12);
            const Vec2 v0{a12, top - a11}, v1{top - a22, a12};
            const Vec2 v = dot(v0, v0) >= dot(v1, v1) ? v0 : v1;
            const double vl = std::sqrt(dot(v, v));
            if (vl > 0 && std::isfinite(vl)) {
                out->seg[k] = (semi / vl) * v;
                out->seg_rho[k] = (shadow.minor + parallax + 1e-6 * semi + 1e-10 * shadow.major) * (1 + 1e-10) + slack;
            }
        }
        if (k == 0) {
            out->m = centre;
            out->rho = radius;
        } else {
            out->cut_m[k - 1] = centre;
            out->cut_rho[k - 1] = radius;
        }
    }
    out->Z = plane;
    return out->Z > 0 && std::isfinite(out->Z) && std::isfinite(out->rho) && is_finite(out->m);
}

Vec3 lens_frame_point(const LensAim& a, Vec3 q)
{
    if (!a.tilted)
        return q;
    const Vec3 c3{a.c.x, a.c.y, a.z};
    return c3 + mul_transposed(a.axes, q - c3);
}

namespace {

// A tilted lens's frame point of q less the lens's centre (lens_frame_point(a, q) - c3, as that
// computes it before adding c3).
Vec3 lens_frame_offset(const LensAim& a, Vec3 q)
{
    const Vec3 c3{a.c.x, a.c.y, a.z};
    return mul_transposed(a.axes, q - c3);
}

} // namespace

// ---- Rounded polygons -------------------------------------------------------------------------

namespace {

// +1 when the corners go counter-clockwise, -1 clockwise, 0 when they enclose no area (fewer than
// three corners, or all on a line).
int orientation(const RoundedPolygon& r)
{
    double area = 0;
    for (int k = 0; k < r.corners; ++k)
        area += cross(r.corner[k], r.corner[(k + 1) % r.corners]);
    return area > 0 ? 1 : (area < 0 ? -1 : 0);
}

// Squared distance from p to the segment a-b.
double segment_distance2(Vec2 p, Vec2 a, Vec2 b)
{
    const Vec2 e = b - a, q = p - a;
    const double length2 = dot(e, e);
    double t = length2 > 0 ? dot(q, e) / length2 : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    const double dx = q.x - t * e.x, dy = q.y - t * e.y;
    return dx * dx + dy * dy;
}

// A rounded polygon's boundary pieces for its chords: the circles about its corners and its edges
// moved out by the radius (both ways when the polygon encloses no area).
struct Outline {
    int corners;
    Vec2 corner[8];
    double radius, radius2;
    int edges;
    Vec2 p[16], q[16];
    int side[16];  // +1: on the upper boundary (outward normal up), -1: the lower, 0: vertical
};

void make_outline(const RoundedPolygon& r, Outline* o)
{
    o->corners = r.corners;
    for (int k = 0; k < r.corners; ++k)
        o->corner[k] = r.corner[k];
    o->radius = r.radius;
    o->radius2 = r.radius * r.radius;
    o->edges = 0;
    const int turn = orientation(r);
    for (int k = 0; k < r.corners; ++k) {
        const Vec2 a = r.corner[k], b = r.corner[(k + 1) % r.corners];
        const Vec2 e = b - a;
        const double length = std::sqrt(dot(e, e));
        if (!(length > 0))
            continue;
        for (int side = -1; side <= 1; side += 2) {
            if (turn != 0 && side != turn)
                continue;
            const Vec2 n{side * e.y / length * r.radius, -side * e.x / length * r.radius};
            o->p[o->edges] = a + n;
            o->q[o->edges] = b + n;
            const double up = -side * e.x;  // the outward normal's y, times the length
            o->side[o->edges] = up > 0 ? 1 : (up < 0 ? -1 : 0);
            ++o->edges;
        }
    }
}

// The chord's ends at x: the lower one when `lower`, the upper one when `upper` (else -inf, +inf);
// false when x lies outside the region's x range.
bool outline_chord(const Outline& o, double x, bool lower, bool upper, double* y0, double* y1)
{
    // The boundary of a convex polygon widened by a disc is made of its edges moved out by the
    // radius along their normals and of arcs about its corners; every point of those pieces (whole
    // circles about the corners included) lies in the region, so the chord runs from the lowest to
    // the highest of them at x (the highest on an arc or an edge facing up or sideways).
    double lo = INFINITY, hi = -INFINITY;
    bool any = false;
    for (int k = 0; k < o.corners; ++k) {
        const Vec2 v = o.corner[k];
        const double dx = x - v.x;
        if (std::fabs(dx) <= o.radius) {
            any = true;
            const double h = std::sqrt(std::max(0.0, o.radius2 - dx * dx));
            lo = std::min(lo, v.y - h);
            hi = std::max(hi, v.y + h);
        }
    }
    for (int k = 0; k < o.edges; ++k) {
        if (!(o.side[k] > 0 ? upper : (o.side[k] < 0 ? lower : true)))
            continue;
        const Vec2 p = o.p[k], q = o.q[k];
        if (!(x >= std::min(p.x, q.x) && x <= std::max(p.x, q.x)))
            continue;
        any = true;
        if (p.x == q.x) {
            lo = std::min(lo, std::min(p.y, q.y));
            hi = std::max(hi, std::max(p.y, q.y));
            continue;
        }
        double t = (x - p.x) / (q.x - p.x);
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        const double y = p.y + t * (q.y - p.y);
        lo = std::min(lo, y);
        hi = std::max(hi, y);
    }
    *y0 = lower ? lo : -INFINITY;
    *y1 = upper ? hi : INFINITY;
    return any;
}

} // namespace

bool region_holds(const RoundedPolygon& r, Vec2 p)
{
    const int turn = orientation(r);
    if (turn != 0) {
        bool inside = true;
        for (int k = 0; k < r.corners && inside; ++k) {
            const Vec2 a = r.corner[k], b = r.corner[(k + 1) % r.corners];
            inside = turn * cross(b - a, p - a) >= 0;
        }
        if (inside)
            return true;
    }
    for (int k = 0; k < r.corners; ++k)
        if (segment_distance2(p, r.corner[k], r.corner[(k + 1) % r.corners]) <= r.radius * r.radius)
            return true;
    return false;
}

void region_x_extent(const RoundedPolygon& r, double* x0, double* x1)
{
    double lo = r.corner[0].x, hi = r.corner[0].x;
    for (int k = 1; k < r.corners; ++k) {
        lo = std::min(lo, r.corner[k].x);
        hi = std::max(hi, r.corner[k].x);
    }
    *x0 = lo - r.radius;
    *x1 = hi + r.radius;
}

bool region_chord(const RoundedPolygon& r, double x, double* y0, double* y1)
{
    Outline o;
    make_outline(r, &o);
    return outline_chord(o, x, true, true, y0, y1) && *y1 >= *y0;
}

// The convex polygon r widened by the segment from -u to u. Each edge moves by whichever of -u, +u
// lies along its outward normal, and where that choice changes (twice around a convex polygon) the
// segment's own edge joins the two: n + 2 corners. Where the sides do not change exactly twice
// (a polygon with no area; rounding on edges nearly along u), the convex hull of the corners moved
// both ways instead (Andrew's monotone chain; collinear corners dropped). False, r unchanged, when
// the result has more corners than a RoundedPolygon holds.
bool widen_by_segment(RoundedPolygon* r, Vec2 u)
{
    const int capacity = int(sizeof(r->corner) / sizeof(r->corner[0]));
    const int turn = orientation(*r);
    if (turn != 0 && r->corners >= 3 && r->corners + 2 <= capacity) {
        int side[sizeof(r->corner) / sizeof(r->corner[0])];
        int changes = 0;
        for (int k = 0; k < r->corners; ++k) {
            const Vec2 e = r->corner[(k + 1) % r->corners] - r->corner[k];
            side[k] = turn * (e.y * u.x - e.x * u.y) >= 0 ? 1 : -1;
        }
        for (int k = 0; k < r->corners; ++k)
            changes += side[k] != side[(k + 1) % r->corners] ? 1 : 0;
        if (changes == 2) {
            Vec2 out[sizeof(r->corner) / sizeof(r->corner[0])];
            int count = 0;
            for (int k = 0; k < r->corners; ++k) {
                const int next = (k + 1) % r->corners;
                const Vec2 c = r->corner[next];
                out[count++] = c + double(side[k]) * u;
                if (side[next] != side[k])
                    out[count++] = c + double(side[next]) * u;
            }
            r->corners = count;
            for (int k = 0; k < count; ++k)
                r->corner[k] = out[k];
            return true;
        }
    }
    Vec2 points[16];
    int n = 0;
    for (int k = 0; k < r->corners; ++k) {
        points[n++] = r->corner[k] - u;
        points[n++] = r->corner[k] + u;
    }
    Vec2 hull[32];
    const int h = convex_hull(points, n, hull);
    if (!(h >= 1 && h <= capacity))
        return false;
    r->corners = h;
    for (int k = 0; k < h; ++k)
        r->corner[k] = hull[k];
    return true;
}

RoundedPolygon lit_sensor_region(const LensAim& a, double d, int cut)
{
    // s lies in the region when the lit cell disc's centre (m - c + (Z/d)(s - c)) / g lies within
    // rho / |g| of the cell H: s - c - (c - m) d/Z in (d/Z) g (H + disc(rho/|g|)), and H is
    // symmetric about its centre.
    const Vec2 m = cut < 0 ? a.m : a.cut_m[cut];
    const double rho = a.disc_rho(cut);
    const double g = 1 + a.Z / d - a.Z / a.f;
    const double k = d / a.Z;
    const Vec2 shift{(a.c.x - m.x) * k, (a.c.y - m.y) * k};
    const Vec2 centre{a.c.x + shift.x, a.c.y + shift.y};
    const double scale = std::fabs(g) * k;
    RoundedPolygon out;
    Vec2 cell[6];
    out.corners = cell_polygon(a.grid, a.pitch, cell);
    for (int n = 0; n < out.corners; ++n)
        out.corner[n] = Vec2{centre.x + scale * cell[n].x, centre.y + scale * cell[n].y};
    // A tilted lens's stadium (LensAim::seg) in place of its flattened disc: the cell's polygon
    // widened by the segment (the hull of its corners moved both ways along it), then rounded.
    const Vec2 half = a.seg[cut + 1];
    const bool stadium = a.has_stadium(cut) && widen_by_segment(&out, Vec2{half.x * k, half.y * k});
    const double radius = (stadium ? a.pixel_rho(cut) : rho) * k;
    // g's rounding is up to ~1e-16 of (1 + Z/d + Z/|f|), the scale's of that times d/Z.
    const double slack =
        kRoundingMargin * (std::fabs(shift.x) + std::fabs(shift.y) + radius + std::fabs(a.c.x) + std::fabs(a.c.y) +
                           (scale + k + 1 + d / std::fabs(a.f)) * a.circumradius + (stadium ? length(half) * k : 0));
    out.radius = radius * (1 + kRoundingMargin) + slack;
    return out;
}

namespace {

// How far, at most, the boundary of a lens's region for disc k (lit_sensor_region) moves per unit
// of the sensor's distance about d, over a change of up to `change`: the region is
// C(d) + S(d) H + rho(d) B (B the unit disc), C = c + (c - m) d/Z, S = |1 + d (1/Z - 1/f)|,
// rho(d) = rho d/Z, so its support function along a unit n is C.n + S h_H(n) + rho(d), h_H(n)
// between the cell's inradius and `extent` (the circumradius; the inradius alone for the
// inscribed disc); its rate |C'| + |S' h_H + rho'| at most, both ends tried (S' keeps its sign
// while 1 + d (1/Z - 1/f) does; else the sum of the rates' sizes).
double region_drift(const LensAim& a, int cut, double d, double change, double extent)
{
    const Vec2 m = cut < 0 ? a.m : a.cut_m[cut];
    // A stadium's segment adds |n.seg| d/Z to the support function: a rate of at most |seg| / Z.
    const double centre = (std::hypot(a.c.x - m.x, a.c.y - m.y) + length(a.seg[cut + 1])) / a.Z,
                 radius = a.pixel_rho(cut) / a.Z;
    const double slope = 1 / a.Z - 1 / a.f, at = 1 + d * slope;
    const double inradius = 0.5 * a.pitch;
    if (!(std::fabs(at) > std::fabs(change * slope) * (1 + 1e-9)))
        return centre + std::fabs(slope) * extent + radius;
    const double scale = at > 0 ? slope : -slope;
    return centre + std::max(std::fabs(scale * inradius + radius), std::fabs(scale * extent + radius));
}

} // namespace

RoundedPolygon sensor_region(const LensAim& a, Vec3 s, double reach, int cut)
{
    if (!a.tilted)
        return lit_sensor_region(a, a.z - s.z, cut);
    // The plane's points within reach of s lie, in the lens's frame, within reach of its (x, y) and
    // within reach sin t of its distance (the lens's axis is t off the array's normal).
    const Vec3 t = lens_frame_point(a, s);
    const double change = reach * a.sin_tilt;
    RoundedPolygon r = lit_sensor_region(a, a.z - t.z, cut);
    r.radius += change * region_drift(a, cut, a.z - t.z, change, a.circumradius) * (1 + 1e-9);
    // Back to the plane: a point q of it has lens-frame (x, y) = c + B (q - c) + b (q.z - z) (B, b:
    // the first two rows of axes^T), so q = c + B^-1 (p - c - b (q.z - z)); B's smaller singular
    // value is |cos t| (axes^T is a rotation), so a radius grows by at most 1 / |cos t|.
    const Mat3& A = a.axes;
    const double b00 = A.m[0][0], b01 = A.m[1][0], b10 = A.m[0][1], b11 = A.m[1][1];
    const double det = b00 * b11 - b01 * b10;
    const double rise = s.z - a.z;
    const Vec2 shift{A.m[2][0] * rise, A.m[2][1] * rise};
    double scale = 0;
    for (int n = 0; n < r.corners; ++n) {
        const double x = r.corner[n].x - a.c.x - shift.x, y = r.corner[n].y - a.c.y - shift.y;
        r.corner[n] = Vec2{a.c.x + (b11 * x - b01 * y) / det, a.c.y + (-b10 * x + b00 * y) / det};
        scale += std::fabs(r.corner[n].x) + std::fabs(r.corner[n].y);
    }
    r.radius = r.radius / std::fabs(A.m[2][2]) * (1 + 1e-12) + 1e-12 * scale;
    return r;
}

int own_sensor_cell(const PlenopticCamera& m, LensIndex lens, double sensor_z, HalfPlane out[8])
{
    // own_lens projects the sensor point s from the exit pupil's centre e onto the array's plane
    // (array-local z = 0), q = e + (s - e) / K with K = (e.z - sensor_z) / e.z, and takes the lens
    // whose centre is nearest q (MicrolensArray::nearest). q is nearer centre a than centre b when
    // (b - a) . q <= (b - a) . (a + b) / 2, i.e. (b - a) . s <= (b - a) . (e + K ((a + b) / 2 - e)).
    if (!m.lens)
        return 0;
    const Vec3 e = m.array.to_local(m.lens->exit_pupil_centre());
    const double K = (e.z - sensor_z) / e.z;
    if (!(K > 0) || !std::isfinite(K) || !is_finite(e))
        return 0;
    const Vec2 a = m.array.centre_local(lens);
    LensIndex adjacent[8];
    const int n_adjacent = adjacent_lenses(m.array.grid, lens, adjacent);
    int count = 0;
    for (int q = 0; q < n_adjacent; ++q) {
        const Vec2 b = m.array.centre_local(adjacent[q]);
        const Vec2 n{b.x - a.x, b.y - a.y};
        const Vec2 mid{e.x + K * (0.5 * (a.x + b.x) - e.x), e.y + K * (0.5 * (a.y + b.y) - e.y)};
        const double scale = std::fabs(n.x) + std::fabs(n.y);
        const double slack = kRoundingMargin * scale *
                             (std::fabs(e.x) + std::fabs(e.y) +
                              K * (std::fabs(a.x) + std::fabs(a.y) + std::fabs(b.x) + std::fabs(b.y) + std::fabs(e.x) +
                                   std::fabs(e.y)));
        out[count++] = HalfPlane{n, dot(n, mid) + slack};
    }
    return count;
}

namespace {

inline AimDisc cell_disc(const LensAim& a, Vec3 s, Vec2 m, double rho)
{
    // g h - (Z/d) s + (Z/f) c within rho of m; from the lens's centre: h - c within rho / |g| of
    // (m - c + (Z/d) (s - c)) / g.
    const double d = a.z - s.z;
    const double g = 1 + a.Z / d - a.Z / a.f;
    if (!(g != 0) || !std::isfinite(g))
        return AimDisc{Vec2{0, 0}, std::numeric_limits<double>::infinity()};
    const double k = a.Z / d;
    const double x = m.x - a.c.x + k * (s.x - a.c.x), y = m.y - a.c.y + k * (s.y - a.c.y);
    const double slack = kRoundingMargin * (std::fabs(x) + std::fabs(y) + rho) / std::fabs(g);
    return AimDisc{Vec2{x / g, y / g}, rho / std::fabs(g) * (1 + kRoundingMargin) + slack};
}

// The x range of the convex polygon (n corners, in order) within every disc (finite radii). The
// extreme points of an intersection of convex sets lie on its boundary, made of the parts of the
// polygon's edges within every disc and of the parts of the circles within the polygon and the
// other discs; x is extreme on an edge's part at its ends, on a circle's part at the circle's
// leftmost or rightmost point or at the part's ends (on an edge, counted there, or on another
// circle). So: each edge clipped by every disc, and the circles' extreme points and crossings that
// lie in the polygon and the other discs (to rounding).
bool polygon_discs_x_range(const Vec2* corner, int n, const AimDisc* discs, int count, double* x0, double* x1)
{
    double scale = 0;
    for (int k = 0; k < n; ++k)
        scale += std::fabs(corner[k].x) + std::fabs(corner[k].y);
    for (int k = 0; k < count; ++k)
        scale += discs[k].radius + std::fabs(discs[k].centre.x) + std::fabs(discs[k].centre.y);
    const double tolerance = 1e-12 * scale;
    double lo = INFINITY, hi = -INFINITY;
    // The corners within every disc; an edge between two of them lies within them all.
    bool inside[6];
    for (int e = 0; e < n; ++e) {
        inside[e] = true;
        for (int k = 0; k < count && inside[e]; ++k) {
            const double dx = corner[e].x - discs[k].centre.x, dy = corner[e].y - discs[k].centre.y;
            inside[e] = dx * dx + dy * dy <= discs[k].radius * discs[k].radius;
        }
        if (inside[e]) {
            lo = std::min(lo, corner[e].x);
            hi = std::max(hi, corner[e].x);
        }
    }
    // The other edges a + t (b - a), 0 <= t <= 1, within every disc: |a + t v - c|^2 <= r^2 (those
    // whose x span lies within the range so far cannot widen it).
    for (int e = 0; e < n; ++e) {
        const int f = (e + 1) % n;
        if (inside[e] && inside[f])
            continue;
        const Vec2 a = corner[e], b = corner[f];
        if (std::min(a.x, b.x) >= lo && std::max(a.x, b.x) <= hi)
            continue;
        const Vec2 v = b - a;
        const double A = dot(v, v);
        if (!(A > 0))
            continue;
        double t0 = 0, t1 = 1;
        for (int k = 0; k < count && t0 <= t1; ++k) {
            const Vec2 w = a - discs[k].centre;
            const double B = dot(v, w), C = dot(w, w) - discs[k].radius * discs[k].radius;
            const double disc = B * B - A * C;
            if (!(disc >= 0)) {
                t1 = -1;
                break;
            }
            // Without cancellation: q = -(B + sign(B) root), roots q / A and C / q.
            const double root = std::sqrt(disc);
            const double q = -(B + (B < 0 ? -root : root));
            double r0 = q / A, r1 = q != 0 ? C / q : r0;
            if (r0 > r1)
                std::swap(r0, r1);
            t0 = std::max(t0, r0);
            t1 = std::min(t1, r1);
        }
        if (!(t0 <= t1))
            continue;
        const double xa = a.x + t0 * v.x, xb = a.x + t1 * v.x;
        lo = std::min(lo, std::min(xa, xb));
        hi = std::max(hi, std::max(xa, xb));
    }
    double turn = 0;
    for (int k = 0; k < n; ++k)
        turn += cross(corner[k], corner[(k + 1) % n]);
    const double sign = turn >= 0 ? 1 : -1;
    // A point of circle `skip` (and `skip2`): kept if in the polygon and the other discs.
    auto consider = [&](Vec2 p, int skip, int skip2) {
        if (!(p.x < lo || p.x > hi))
            return;
        for (int k = 0; k < n; ++k) {
            const Vec2 a = corner[k], b = corner[(k + 1) % n];
            const Vec2 e = b - a;
            const double c = sign * cross(e, p - a);
            if (c < 0 && c * c > tolerance * tolerance * dot(e, e))
                return;
        }
        for (int k = 0; k < count; ++k) {
            if (k == skip || k == skip2)
                continue;
            const double dx = p.x - discs[k].centre.x, dy = p.y - discs[k].centre.y;
            const double r = discs[k].radius + tolerance;
            if (!(dx * dx + dy * dy <= r * r))
                return;
        }
        lo = std::min(lo, p.x);
        hi = std::max(hi, p.x);
    };
    for (int k = 0; k < count; ++k) {
        const AimDisc& d = discs[k];
        consider(Vec2{d.centre.x - d.radius, d.centre.y}, k, k);
        consider(Vec2{d.centre.x + d.radius, d.centre.y}, k, k);
        for (int o = k + 1; o < count; ++o) {
            const AimDisc& f = discs[o];
            const double dx = f.centre.x - d.centre.x, dy = f.centre.y - d.centre.y;
            const double between = std::sqrt(dx * dx + dy * dy);
            if (!(between > 0) || between > d.radius + f.radius || between < std::fabs(d.radius - f.radius))
                continue;
            const double along = (between * between + d.radius * d.radius - f.radius * f.radius) / (2 * between);
            const double across = std::sqrt(std::max(0.0, d.radius * d.radius - along * along));
            const Vec2 u{dx / between, dy / between};
            const Vec2 base{d.centre.x + along * u.x, d.centre.y + along * u.y};
            consider(Vec2{base.x - across * u.y, base.y + across * u.x}, k, o);
            consider(Vec2{base.x + across * u.y, base.y - across * u.x}, k, o);
        }
    }
    if (!(hi >= lo))
        return false;
    *x0 = lo - tolerance;
    *x1 = hi + tolerance;
    return true;
}

// The cell disc of a tilted lens for disc k of the main lens's plane (lit_cell_disc's comment in
// the header); infinite radius when it cannot be bounded so (then every cell point may pass).
AimDisc tilted_cell_disc(const LensAim& a, Vec3 sp, int k)
{
    const AimDisc all{Vec2{0, 0}, std::numeric_limits<double>::infinity()};
    // In the lens's frame, from its centre: the sensor point sp (lens_frame_offset) at distance d
    // behind its plane; every ray from it leaves cell point P = (h, 0) along X - w P, (X, w) the
    // homogeneous image (-f s_xy, f d, d - f) (w = 0: parallel rays).
    const double d = -sp.z, f = a.f;
    if (!(d > 0) || !(f > 0))
        return all;
    const Vec3 X{-f * sp.x, -f * sp.y, f * d};
    const double w = d - f;
    const Vec3 N = a.disc_normal, M = a.disc_centre[k];
    const double rho = a.disc_radius[k];
    const double NX = dot(N, X), NM = dot(N, M);
    // The ray meets the disc's plane at Q = P + mu (X - w P), mu = N.(M - P) / N.(X - w P); both
    // must be positive over the cell (affine in h: at its corners).
    Vec2 corner[6];
    const int n = cell_polygon(a.grid, a.pitch, corner);
    for (int q = 0; q < n; ++q)
        if (!(NX - w * (N.x * corner[q].x + N.y * corner[q].y) > 0 && NM - (N.x * corner[q].x + N.y * corner[q].y) > 0))
            return all;
    // Times alpha = N.(X - w P) > 0, |Q - M| <= rho reads |u(h)| <= rho alpha(h) with
    // u = (P - M) alpha + N.(M - P) (X - w P), affine in h (the quadratic terms cancel):
    // u0 = (N.M) X - (N.X) M, and u's change along h.x, (N.X - w N.M) x + N.x (w M - X).
    const Vec3 u0 = NM * X - NX * M;
    const Vec3 wm = w * M - X;
    const double q0 = NX - w * NM;
    PlaneEllipse ellipse;
    if (!focus_ellipse(u0, Vec3{q0, 0, 0} + N.x * wm, Vec3{0, q0, 0} + N.y * wm, N, NX, Vec2{-w * N.x, -w * N.y}, rho,
                       &ellipse))
        return all;
    const Vec2 C = ellipse.centre, g0 = ellipse.g0, g1 = ellipse.g1;
    const double Gdet = g0.x * g1.y - g1.x * g0.y;
    const double major = ellipse.major;
    const double radius = major * major / ellipse.minor;
    // The boundary point toward the cell's centre (z on the unit circle with G z along -C) and
    // the inward normal there (G^-T z).
    Vec2 z{(g1.y * -C.x - g1.x * -C.y) / Gdet, (-g0.y * -C.x + g0.x * -C.y) / Gdet};
    const double zl = length(z);
    z = zl > 0 ? (1 / zl) * z : Vec2{1, 0};
    const Vec2 point = C + z.x * g0 + z.y * g1;
    Vec2 normal{(g1.y * z.x - g0.y * z.y) / Gdet, (-g1.x * z.x + g0.x * z.y) / Gdet};
    normal = (1 / length(normal)) * normal;
    const Vec2 centre = point - radius * normal;
    if (!(is_finite(centre) && std::isfinite(radius)))
        return all;
    // Rounding: each step is ~1e-16 of the ellipse's size; 1e-10 of it holds it many times over.
    return AimDisc{centre, radius * (1 + 1e-10) + 1e-10 * (length(C) + major)};
}

// The lens's finite discs of cell points for sensor point s (array-local; the disc and its cuts');
// how many.
int cell_discs(const LensAim& a, Vec3 s_array, AimDisc discs[1 + LensAim::kMaxCuts])
{
    if (a.tilted) {
        // First the flattened discs (lens_aim: they hold where the passing rays from the cell
        // cross the lens frame's plane Z, so their cell discs hold the exact ones): a disc whose
        // cell disc holds the whole cell constrains nothing (most sensor points, inside a
        // microimage), and only the others need their ellipses.
        const Vec3 c3{a.c.x, a.c.y, a.z};
        const Vec3 sp = mul_transposed(a.axes, s_array - c3);  // lens_frame_point's, once
        const Vec3 s = c3 + sp;
        int count = 0;
        for (int k = 0; k <= a.cuts; ++k) {
            const AimDisc flat = k == 0 ? cell_disc(a, s, a.m, a.rho) : cell_disc(a, s, a.cut_m[k - 1], a.cut_rho[k - 1]);
            if (!(flat.radius < std::numeric_limits<double>::infinity()) ||
                std::sqrt(flat.centre.x * flat.centre.x + flat.centre.y * flat.centre.y) + a.circumradius <= flat.radius)
                continue;
            const AimDisc d = tilted_cell_disc(a, sp, k);
            if (d.radius < std::numeric_limits<double>::infinity())
                discs[count++] = d;
        }
        return count;
    }
    const Vec3 s = s_array;
    if (a.cuts == 0) {
        discs[0] = cell_disc(a, s, a.m, a.rho);
        return discs[0].radius < std::numeric_limits<double>::infinity() ? 1 : 0;
    }
    int count = 0;
    for (int k = -1; k < a.cuts; ++k) {
        const AimDisc d = k < 0 ? cell_disc(a, s, a.m, a.rho) : cell_disc(a, s, a.cut_m[k], a.cut_rho[k]);
        if (d.radius < std::numeric_limits<double>::infinity())
            discs[count++] = d;
    }
    return count;
}

// The x range of the cell (centred on 0) within one disc, exactly up to rounding (widened by it,
// as polygon_discs_x_range): the x where the disc's chord meets the cell's column [-h(x), h(x)],
// i.e. where the distance from (x, |y_d|) to that column, max(0, |y_d| - h(x)), is at most the
// disc's reach sqrt(r^2 - (x - x_d)^2). A rectangle's h is constant; a hexagon's
// h = (p - |x|) / sqrt 3 is linear on each half, so there the condition is |x - x_d| <= r where
// h(x) >= |y_d| and a quadratic in |x| where h(x) < |y_d|.
bool cell_disc_x_range(GridType grid, double pitch, const AimDisc& d, double* x0, double* x1)
{
    const double half = 0.5 * pitch;
    const double a = std::fabs(d.centre.y), cx = d.centre.x, r = d.radius;
    double lo = INFINITY, hi = -INFINITY;
    double scale;
    if (grid != GridType::Hexagonal) {
        scale = 4 * pitch;  // the corners' |x| + |y|, as polygon_discs_x_range
        const double beyond = a - half;
        const double w2 = r * r - (beyond > 0 ? beyond * beyond : 0);
        if (w2 >= 0) {
            const double w = std::sqrt(w2);
            lo = std::max(-half, cx - w);
            hi = std::min(half, cx + w);
        }
    } else {
        const double R = pitch / kSqrt3;
        scale = 2 * pitch + 4 * R;
        // h(|x|) >= a for |x| <= p - sqrt(3) a.
        const double within = std::min(half, pitch - kSqrt3 * a);
        if (within >= 0 && std::max(-within, cx - r) <= std::min(within, cx + r)) {
            lo = std::max(-within, cx - r);
            hi = std::min(within, cx + r);
        }
        const double from = std::max(0.0, pitch - kSqrt3 * a);
        if (from <= half) {
            // t = |x| on the side x = side t: (side t - x_d)^2 + (a - R + t / sqrt 3)^2 <= r^2,
            // (4/3) t^2 + 2 B t + C <= 0.
            const double A = 4.0 / 3.0;
            const double C = cx * cx + (a - R) * (a - R) - r * r;
            for (int side = -1; side <= 1; side += 2) {
                const double B = -side * cx + (a - R) / kSqrt3;
                const double disc = B * B - A * C;
                if (!(disc >= 0))
                    continue;
                const double root = std::sqrt(disc);
                const double t0 = std::max(from, (-B - root) / A), t1 = std::min(half, (-B + root) / A);
                if (!(t0 <= t1))
                    continue;
                lo = std::min(lo, side > 0 ? t0 : -t1);
                hi = std::max(hi, side > 0 ? t1 : -t0);
            }
        }
    }
    if (!(hi >= lo))
        return false;
    const double tolerance = 1e-12 * (scale + r + std::fabs(cx) + std::fabs(d.centre.y));
    *x0 = lo - tolerance;
    *x1 = hi + tolerance;
    return true;
}

bool cell_x_range(const LensAim& a, const AimDisc* discs, int count, double* x0, double* x1)
{
    const double half = 0.5 * a.pitch;
    if (count == 0) {
        *x0 = -half;
        *x1 = half;
        return true;
    }
    if (count == 1) {
        if (!cell_disc_x_range(a.grid, a.pitch, discs[0], x0, x1))
            return false;
        *x0 = std::max(*x0, -half);
        *x1 = std::min(*x1, half);
        return *x1 > *x0;
    }
    Vec2 cell[6];
    const int n = cell_polygon(a.grid, a.pitch, cell);
    if (!polygon_discs_x_range(cell, n, discs, count, x0, x1))
        return false;
    *x0 = std::max(*x0, -half);
    *x1 = std::min(*x1, half);
    return *x1 > *x0;
}

} // namespace

AimDisc lit_cell_disc(const LensAim& a, Vec3 s)
{
    return a.tilted ? tilted_cell_disc(a, lens_frame_offset(a, s), 0) : cell_disc(a, s, a.m, a.rho);
}

AimDisc lit_cell_cut(const LensAim& a, Vec3 s, int k)
{
    return a.tilted ? tilted_cell_disc(a, lens_frame_offset(a, s), k + 1) : cell_disc(a, s, a.cut_m[k], a.cut_rho[k]);
}

bool lit_cell_x_range(const LensAim& a, Vec3 s, double* x0, double* x1)
{
    AimDisc discs[1 + LensAim::kMaxCuts];
    const int count = cell_discs(a, s, discs);
    return cell_x_range(a, discs, count, x0, x1);
}

double cell_half_height(GridType grid, double pitch_mm, double x)
{
    const double half = 0.5 * pitch_mm;
    if (!(std::fabs(x) <= half))
        return -1;
    if (grid != GridType::Hexagonal)
        return half;
    // Pointy-topped hexagon (corners at +-R on the y axis, R = p / sqrt 3), sides at x = +-p/2.
    return pitch_mm / kSqrt3 - std::fabs(x) / kSqrt3;
}

namespace {

// Up to kMaxParts intervals, merged into a union that can be sampled uniformly.
const int kMaxParts = 9;
struct Intervals {
    double lo[kMaxParts], hi[kMaxParts];
    int count = 0;
    void add(double a, double b)
    {
        if (!(b > a))
            return;
        int k = count++;
        while (k > 0 && lo[k - 1] > a) {  // keep them sorted by their start
            lo[k] = lo[k - 1];
            hi[k] = hi[k - 1];
            --k;
        }
        lo[k] = a;
        hi[k] = b;
    }
    // Merges overlapping intervals; returns the union's length.
    double merge()
    {
        int out = 0;
        for (int k = 0; k < count; ++k) {
            if (out > 0 && lo[k] <= hi[out - 1]) {
                if (hi[k] > hi[out - 1])
                    hi[out - 1] = hi[k];
            } else {
                lo[out] = lo[k];
                hi[out] = hi[k];
                ++out;
            }
        }
        count = out;
        double total = 0;
        for (int k = 0; k < count; ++k)
            total += hi[k] - lo[k];
        return total;
    }
    // The point at fraction t of the merged union's length.
    double at(double t, double total) const
    {
        double left = t * total;
        for (int k = 0; k < count; ++k) {
            const double length = hi[k] - lo[k];
            if (left < length || k == count - 1)
                return lo[k] + (left < length ? left : length);
            left -= length;
        }
        return lo[0];
    }
};

// Array-local (x, y) in the sensor's plane -> the pixel's own frame: (pixel coordinates - the
// pixel's corner (i, j)) times the pixel's size, in mm. A rigid map (the array is parallel to the
// sensor), so regions keep their radii; the pixel is [0, px] x [0, py].
struct PixelFrame {
    double o[2];
    double l[2][2];
    Vec2 map(Vec2 p) const { return Vec2{o[0] + l[0][0] * p.x + l[0][1] * p.y, o[1] + l[1][0] * p.x + l[1][1] * p.y}; }
};

PixelFrame pixel_frame(const PlenopticCamera& m, double sensor_z, int i, int j)
{
    // Sensor::point: optics x = -(pu - W/2) px + offset, y = (pv - H/2) py + offset; the local
    // point's optics position is pose.centre + rotation * (x, y, sensor_z).
    const Sensor& s = m.sensor;
    const Mat3& r = m.array.pose.rotation;
    const Vec3& c = m.array.pose.centre_mm;
    PixelFrame f;
    f.o[0] = (0.5 * s.film.width - i) * s.pixel_size_mm[0] + s.offset_mm[0] - c.x - r.m[0][2] * sensor_z;
    f.l[0][0] = -r.m[0][0];
    f.l[0][1] = -r.m[0][1];
    f.o[1] = (j - 0.5 * s.film.height) * -s.pixel_size_mm[1] - s.offset_mm[1] + c.y + r.m[1][2] * sensor_z;
    f.l[1][0] = r.m[1][0];
    f.l[1][1] = r.m[1][1];
    return f;
}

// One lens's part: where its light can land (the intersection of `sets`, in the pixel's frame) and
// the x range of that part within the pixel.
const int kMaxSets = 1 + LensAim::kMaxCuts;
struct LensPart {
    int sets;
    RoundedPolygon set[kMaxSets];
    Outline outline[kMaxSets];
    int planes;
    HalfPlane plane[8];
    double x0, x1;
    // Which ends of each set's chord can fall within the pixel's rows over [x0, x1] (the others
    // are beyond them there; sampling asks only for these).
    bool lower[kMaxSets], upper[kMaxSets], plane_needed[8];
};

// The part's chord at x within the pixel's rows [0, py]; its length (negative: none).
double part_chord(const LensPart& part, double x, double py, double* y0, double* y1, bool all = true)
{
    double lo = 0, hi = py;
    for (int k = 0; k < part.sets; ++k) {
        const bool lower = all || part.lower[k], upper = all || part.upper[k];
        if (!(lower || upper))
            continue;
        double a, b;
        if (!outline_chord(part.outline[k], x, lower, upper, &a, &b))
            return -INFINITY;
        lo = std::max(lo, a);
        hi = std::min(hi, b);
    }
    for (int k = 0; k < part.planes; ++k) {
        if (!(all || part.plane_needed[k]))
            continue;
        // n.x x + n.y y <= offset
        const HalfPlane& h = part.plane[k];
        const double rest = h.offset - h.normal.x * x;
        if (h.normal.y > 0)
            hi = std::min(hi, rest / h.normal.y);
        else if (h.normal.y < 0)
            lo = std::max(lo, rest / h.normal.y);
        else if (!(rest >= 0))
            return -INFINITY;
    }
    *y0 = lo;
    *y1 = hi;
    return hi - lo;
}

// Leaves out of an outline the pieces that are nowhere within [x0, x1] (a circle is there where
// |x - corner.x| <= radius, which rounding keeps monotone on each side of the corner; an edge
// between its ends' x) and the edges of the sides not asked for: the chords at x in [x0, x1] stay
// the same, bit for bit, and cost less to sample.
void prune_outline(Outline* o, double x0, double x1, bool lower, bool upper)
{
    int corners = 0;
    for (int k = 0; k < o->corners; ++k) {
        const Vec2 v = o->corner[k];
        if (x0 - v.x > o->radius || v.x - x1 > o->radius)
            continue;
        o->corner[corners++] = v;
    }
    o->corners = corners;
    int edges = 0;
    for (int k = 0; k < o->edges; ++k) {
        const Vec2 p = o->p[k], q = o->q[k];
        if (std::max(p.x, q.x) < x0 || std::min(p.x, q.x) > x1)
            continue;
        if (!(o->side[k] > 0 ? upper : (o->side[k] < 0 ? lower : true)))
            continue;
        o->p[edges] = p;
        o->q[edges] = q;
        o->side[edges] = o->side[k];
        ++edges;
    }
    o->edges = edges;
}

// Which ends of the part's chords can fall within the pixel's rows [0, py] over [x0, x1] (each
// set present at both ends): part_chord(..., all = false) skips the others, with the same result
// there, bit for bit.
void mark_needed(LensPart* part, double x0, double x1, double py)
{
    // A chord's upper end is concave in x, its lower end convex, a half-plane's bound linear: each
    // is beyond the pixel's rows over [x0, x1] when it is at both ends.
    for (int k = 0; k < part->sets; ++k) {
        double a0, b0, a1, b1;
        const bool both = outline_chord(part->outline[k], x0, true, true, &a0, &b0) &&
                          outline_chord(part->outline[k], x1, true, true, &a1, &b1);
        part->lower[k] = !(both && a0 <= 0 && a1 <= 0);
        part->upper[k] = !(both && b0 >= py && b1 >= py);
    }
    for (int k = 0; k < part->planes; ++k) {
        const HalfPlane& h = part->plane[k];
        bool beyond = false;
        if (h.normal.y > 0)
            beyond = (h.offset - h.normal.x * x0) / h.normal.y >= py &&
                     (h.offset - h.normal.x * x1) / h.normal.y >= py;
        else if (h.normal.y < 0)
            beyond = (h.offset - h.normal.x * x0) / h.normal.y <= 0 &&
                     (h.offset - h.normal.x * x1) / h.normal.y <= 0;
        else
            beyond = h.offset - h.normal.x * x0 >= 0 && h.offset - h.normal.x * x1 >= 0;
        part->plane_needed[k] = !beyond;
    }
}

// The x range of the part within the pixel [0, px] x [0, py]; false when empty. The chord's length
// at x is a concave function over the sets' common x range (a minimum of concave upper ends less a
// maximum of convex lower ones), so the range is where it is >= 0: a point there is found by
// golden-section search for the maximum, the ends by bisection to 1e-10 of the pixel, each end
// taken on the outer side.
bool part_x_range(LensPart* part, double px, double py)
{
    // A set farther from the pixel's centre than its radius and half the pixel's diagonal, or a
    // half-plane that leaves out all four corners, leaves out the whole pixel.
    const Vec2 middle{0.5 * px, 0.5 * py};
    const double reach = 0.5 * std::sqrt(px * px + py * py);
    for (int k = 0; k < part->sets; ++k) {
        const RoundedPolygon& r = part->set[k];
        const double far = r.radius + reach;
        if (!region_holds(RoundedPolygon{r.corners, {r.corner[0], r.corner[1], r.corner[2], r.corner[3], r.corner[4],
                                                     r.corner[5]},
                                         far},
                          middle))
            return false;
    }
    for (int k = 0; k < part->planes; ++k) {
        const HalfPlane& h = part->plane[k];
        bool out = true;
        for (int c = 0; c < 4 && out; ++c)
            out = dot(h.normal, Vec2{(c & 1) * px, (c >> 1) * py}) > h.offset;
        if (out)
            return false;
    }
    double a = 0, b = px;
    for (int k = 0; k < part->sets; ++k) {
        const RoundedPolygon& r = part->set[k];
        double x0, x1;
        region_x_extent(r, &x0, &x1);
        a = std::max(a, x0);
        b = std::min(b, x1);
        double y0 = r.corner[0].y, y1 = r.corner[0].y;
        for (int n = 1; n < r.corners; ++n) {
            y0 = std::min(y0, r.corner[n].y);
            y1 = std::max(y1, r.corner[n].y);
        }
        if (!(y1 + r.radius >= 0 && y0 - r.radius <= py))
            return false;
    }
    if (!(b > a))
        return false;
    // The search asks for chords within [a, b] only, and for their ends that can fall within the
    // pixel's rows there.
    for (int k = 0; k < part->sets; ++k)
        prune_outline(&part->outline[k], a, b, true, true);
    mark_needed(part, a, b, py);
    double y0, y1;
    const double fa = part_chord(*part, a, py, &y0, &y1, false), fb = part_chord(*part, b, py, &y0, &y1, false);
    double inside = a;
    if (fa >= 0) {
        inside = a;
    } else if (fb >= 0) {
        inside = b;
    } else {
        const double ratio = 0.5 * (std::sqrt(5.0) - 1);
        double lo = a, hi = b;
        double x1 = hi - ratio * (hi - lo), x2 = lo + ratio * (hi - lo);
        double f1 = part_chord(*part, x1, py, &y0, &y1, false), f2 = part_chord(*part, x2, py, &y0, &y1, false);
        bool found = false;
        for (int n = 0; n < 200; ++n) {
            if (f1 >= 0 || f2 >= 0) {
                inside = f1 >= 0 ? x1 : x2;
                found = true;
                break;
            }
            if (!(hi - lo > 1e-13 * px))
                break;
            if (f1 < f2) {
                lo = x1;
                x1 = x2;
                f1 = f2;
                x2 = lo + ratio * (hi - lo);
                f2 = part_chord(*part, x2, py, &y0, &y1, false);
            } else {
                hi = x2;
                x2 = x1;
                f2 = f1;
                x1 = hi - ratio * (hi - lo);
                f1 = part_chord(*part, x1, py, &y0, &y1, false);
            }
        }
        if (!found)
            return false;
    }
    const double tolerance = 1e-10 * px;
    // An end of the range that is dark: the boundary between it and the lit point `inside`,
    // bisected to the tolerance; its dark end, so that the range holds every lit x.
    const auto dark_end = [&](double dark, double lit) {
        for (int n = 0; n < 200 && std::fabs(lit - dark) > tolerance; ++n) {
            const double mid = 0.5 * (dark + lit);
            if (!(mid > std::min(dark, lit) && mid < std::max(dark, lit)))
                break;
            (part_chord(*part, mid, py, &y0, &y1, false) >= 0 ? lit : dark) = mid;
        }
        return dark;
    };
    part->x0 = fa >= 0 ? a : dark_end(a, inside);
    part->x1 = fb >= 0 ? b : dark_end(b, inside);
    if (!(part->x1 > part->x0))
        return false;
    mark_needed(part, part->x0, part->x1, py);
    for (int k = 0; k < part->sets; ++k)
        prune_outline(&part->outline[k], part->x0, part->x1, part->lower[k], part->upper[k]);
    return true;
}

// A pixel's aim, worked out once for all its samples: its points are uniform (the whole pixel may be
// lit), none (no light reaches it), or drawn from the union of `count` lenses' parts, whose x ranges
// within the pixel are `xs` (of total length `width`), in the pixel's frame.
struct PixelPlan {
    enum Kind { Uniform, Dark, Aimed } kind;
    bool forced;
    LensIndex lens;
    int count;
    LensPart parts[kMaxParts];
    Intervals xs;
    double width;
    double px, py;
};

// A lens's part for the pixel (centre s, array-local; its points within reach of it): its region
// and its cuts', and when the lens is taken as the sensor points' own lens, its projected cell;
// false when one is not finite.
bool lens_part(const PlenopticCamera& m, const LensAim& a, Vec3 s, double reach, const PixelFrame& frame, bool own,
               LensPart* part)
{
    const double d = a.z - lens_frame_point(a, s).z;
    if (!(d > 0))
        return false;
    part->sets = 0;
    for (int k = -1; k < a.cuts; ++k)
        part->set[part->sets++] = sensor_region(a, s, reach, k);
    part->planes = own ? own_sensor_cell(m, a.lens, s.z, part->plane) : 0;
    // Into the pixel's frame; its rounding is ~1e-16 of the frame's offsets.
    const double slack = 1e-13 * (std::fabs(frame.o[0]) + std::fabs(frame.o[1]));
    for (int k = 0; k < part->planes; ++k) {
        // n . s <= b with s = L^T (p - o) (L is a rotation, or one with a reflection): (L n) . p <= b + (L n) . o.
        HalfPlane& h = part->plane[k];
        const Vec2 n{frame.l[0][0] * h.normal.x + frame.l[0][1] * h.normal.y,
                     frame.l[1][0] * h.normal.x + frame.l[1][1] * h.normal.y};
        h = HalfPlane{n, h.offset + n.x * frame.o[0] + n.y * frame.o[1] +
                             slack * (std::fabs(n.x) + std::fabs(n.y))};
        if (!(is_finite(h.normal) && std::isfinite(h.offset)))
            return false;
    }
    for (int k = 0; k < part->sets; ++k) {
        RoundedPolygon& r = part->set[k];
        for (int n = 0; n < r.corners; ++n) {
            r.corner[n] = frame.map(r.corner[n]);
            if (!is_finite(r.corner[n]))
                return false;
        }
        r.radius += slack + 1e-13 * (std::fabs(r.corner[0].x) + std::fabs(r.corner[0].y));
        if (!(r.radius >= 0 && std::isfinite(r.radius)))
            return false;
        make_outline(r, &part->outline[k]);
    }
    part->x0 = part->x1 = 0;
    return true;
}

bool holds_pixel(const LensPart& part, double px, double py)
{
    for (int b = 0; b < 2; ++b)
        for (int a = 0; a < 2; ++a) {
            const Vec2 p{a * px, b * py};
            for (int k = 0; k < part.sets; ++k)
                if (!region_holds(part.set[k], p))
                    return false;
            for (int k = 0; k < part.planes; ++k)
                if (!(dot(part.plane[k].normal, p) <= part.plane[k].offset))
                    return false;
        }
    return true;
}

// Whether the lens's region (lit_sensor_region, within the circle about its centre of radius the
// cell's circumradius scaled by |g| d/Z plus rho d/Z) lies, with a margin, farther than `reach`
// from the pixel's centre s (array-local): then part_x_range would drop the lens's part (its
// region widened by reach leaves out the centre), so the part need not be made. False when unsure.
bool region_far(const LensAim& a, Vec3 s_array, double reach)
{
    // A tilted lens: in its frame, where the pixel's points lie within reach of s's (x, y) and
    // reach sin t of its distance, over which the region moves (region_drift).
    const Vec3 s = lens_frame_point(a, s_array);
    const double d = a.z - s.z;
    if (!(d > 0))
        return false;
    const double k = d / a.Z;
    const double g = 1 + a.Z / d - a.Z / a.f;
    // The margin far exceeds the regions' widening for rounding (1e-12 of their terms).
    const double margin = 1e-9 * (std::fabs(a.c.x) + std::fabs(a.c.y) + std::fabs(a.m.x) + std::fabs(a.m.y) +
                                  std::fabs(s.x) + std::fabs(s.y) + d + (k + 1 + d / std::fabs(a.f)) * a.circumradius);
    const double drift =
        a.tilted ? reach * a.sin_tilt * region_drift(a, -1, d, reach * a.sin_tilt, a.circumradius) : 0;
    const double outer = (a.circumradius * std::fabs(g) * k + a.rho * k + drift) * (1 + 1e-9) + reach + margin;
    const double dx = s.x - (a.c.x + (a.c.x - a.m.x) * k), dy = s.y - (a.c.y + (a.c.y - a.m.y) * k);
    return dx * dx + dy * dy > outer * outer && std::isfinite(outer);
}

// A cheap test that the lens's part holds the whole pixel (centre s, array-local), conservative:
// the pixel lies within the inscribed disc of each region (about its centre c + (c - m) d/Z, of
// radius the cell's inradius p/2 scaled by |g| d/Z, plus rho d/Z), and, when q (the centre's
// projection onto the array from the exit pupil's centre) is given, the pixel's projection lies
// within the inscribed disc of the lens's own cell (about its displaced centre, radius p/2 less the
// largest displacement: the neighbours' centres are at least p less twice that away). Shrunk by
// 1e-9, far beyond the rounding; when it fails, lens_part and holds_pixel decide.
bool inner_holds_pixel(const PlenopticCamera& m, const LensAim& a, Vec3 s_array, const Vec2* q, double px, double py)
{
    // A tilted lens: as region_far.
    const Vec3 s = lens_frame_point(a, s_array);
    const double d = a.z - s.z;
    if (!(d > 0))
        return false;
    const double reach = 0.5 * std::sqrt(px * px + py * py);
    const double k = d / a.Z;
    const double g = 1 + a.Z / d - a.Z / a.f;
    const double inradius = 0.5 * a.pitch * std::fabs(g) * k;
    for (int cut = -1; cut < a.cuts; ++cut) {
        const Vec2 mm = cut < 0 ? a.m : a.cut_m[cut];
        // A stadium (LensAim::seg): the region holds the points within the cell's inscribed radius
        // plus the stadium's radius of its segment (scaled by d/Z), not only of its centre.
        const Vec2 half = a.seg[cut + 1];
        const double rho = a.pixel_rho(cut);
        const double drift =
            a.tilted ? reach * a.sin_tilt * region_drift(a, cut, d, reach * a.sin_tilt, 0.5 * a.pitch) : 0;
        const double room = (inradius + rho * k - drift) * (1 - 1e-9) - reach;
        if (!(room > 0))
            return false;
        double dx = s.x - (a.c.x + (a.c.x - mm.x) * k), dy = s.y - (a.c.y + (a.c.y - mm.y) * k);
        if (a.has_stadium(cut)) {
            // To the segment's nearest point (its ends at -+ half k).
            const double hx = half.x * k, hy = half.y * k;
            double t = (dx * hx + dy * hy) / (hx * hx + hy * hy);
            t = t < -1 ? -1 : (t > 1 ? 1 : t);
            dx -= t * hx;
            dy -= t * hy;
        }
        if (!(dx * dx + dy * dy <= room * room))
            return false;
    }
    if (q) {
        const Vec3 e = m.lens->exit_pupil_centre();
        const double scale = (m.array.pose.centre_mm.z - e.z) / (m.sensor.z_mm - e.z);
        const double shift = m.array.errors ? m.array.errors->max_shift_mm() : 0;
        const double room = (0.5 * a.pitch - shift) * (1 - 1e-9) - reach * std::fabs(scale);
        if (!(room > 0) || !std::isfinite(scale))
            return false;
        const double dx = q->x - a.c.x, dy = q->y - a.c.y;
        if (!(dx * dx + dy * dy <= room * room))
            return false;
    }
    return true;
}

void plan_pixel(const PlenopticCamera& m, int i, int j, const LensIndex* forced, PixelPlan* plan)
{
    plan->kind = PixelPlan::Uniform;
    plan->forced = forced != nullptr;
    plan->count = 0;
    plan->px = m.sensor.pixel_size_mm[0];
    plan->py = m.sensor.pixel_size_mm[1];
    const double px = plan->px, py = plan->py;
    const Vec3 middle = m.sensor.point(i + 0.5, j + 0.5);
    LensIndex lens;
    Vec2 q;  // the centre's projection onto the array (own_lens)
    if (forced) {
        lens = *forced;
    } else {
        if (!detail::project_to_array(m, middle, &q))
            return;
        lens = m.array.nearest(q.x, q.y);
    }
    plan->lens = lens;
    LensAim a;
    const Vec3 s = m.array.to_local(middle);
    if (!(px > 0 && py > 0) || !lens_aim(m, lens, &a))
        return;  // the whole pixel may be lit: its own points, as the uniform samples
    if (inner_holds_pixel(m, a, s, forced ? nullptr : &q, px, py))
        return;  // most pixels: no part to make
    const PixelFrame frame = pixel_frame(m, s.z, i, j);
    LensPart own_part;
    const double reach = 0.5 * std::sqrt(px * px + py * py);
    if (!lens_part(m, a, s, reach, frame, !forced, &own_part))
        return;
    if (holds_pixel(own_part, px, py))
        return;
    // The lenses that can light the pixel: the forced lens; or, for the pixel's own lenses, the
    // lens of its centre and its neighbours (the lattice cells a pixel far smaller than a cell can
    // meet: checked below).
    int count = 0;
    if (forced) {
        plan->parts[count++] = own_part;
    } else {
        // Through the exit pupil's centre e the pixel projects onto the array scaled by
        // (array - e) / (sensor - e), into the disc of radius delta about its centre's projection
        // q. A lens whose cell (about its displaced centre) holds a point x of that disc is nearer
        // x than the centre's own lens is, so its displaced centre lies within
        // |q - the own lens's| + 2 delta of q, and its lattice place within that plus the largest
        // displacement. While that stays below 1.15 pitch (the nearest lattice lens's second ring
        // is farther from any point of its cell), those lenses are that lattice lens and its
        // neighbours; the ones nearer than that are kept.
        const Vec3 e = m.lens->exit_pupil_centre();
        const double scale = (m.array.pose.centre_mm.z - e.z) / (m.sensor.z_mm - e.z);
        const double delta = 0.5 * std::hypot(px, py) * std::fabs(scale);
        const double shift = m.array.errors ? m.array.errors->max_shift_mm() : 0;
        const Vec2 own_centre = m.array.centre_local(lens);
        const double margin = 1e-9 * (std::fabs(q.x) + std::fabs(q.y) + m.array.pitch_mm);
        const double near = std::hypot(q.x - own_centre.x, q.y - own_centre.y) + 2 * delta + margin;
        if (!(near + shift < 1.15 * m.array.pitch_mm))
            return;
        const GridType grid = m.array.grid;
        const LensIndex middle_lens = nearest_lens(grid, m.array.pitch_mm, q.x, q.y);
        const std::int64_t skew = skew_k(grid, middle_lens);
        for (int dl = -1; dl <= 1; ++dl)
            for (int dk = -1; dk <= 1; ++dk) {
                if (grid == GridType::Hexagonal && std::abs(dk + dl) > 1)
                    continue;  // not a neighbour in skew indices
                const LensIndex other = from_skew(grid, skew + dk, middle_lens.l + dl);
                if (other == lens) {
                    plan->parts[count] = own_part;
                } else {
                    const Vec2 place = m.array.lattice_centre_local(other);
                    const double dx = q.x - place.x, dy = q.y - place.y;
                    if (dx * dx + dy * dy > (near + shift) * (near + shift))
                        continue;
                    if (shift > 0) {
                        const Vec2 c = m.array.centre_local(other);
                        const double cx = q.x - c.x, cy = q.y - c.y;
                        if (cx * cx + cy * cy > near * near)
                            continue;
                    }
                    if (!lens_aim(m, other, &a))
                        return;
                    if (region_far(a, s, reach))
                        continue;  // part_x_range would drop it
                    if (!lens_part(m, a, s, reach, frame, true, &plan->parts[count]))
                        return;
                }
                ++count;
            }
    }
    // x: the union over the parts of their exact x ranges within the pixel.
    plan->xs = Intervals();
    int kept = 0;
    for (int k = 0; k < count; ++k) {
        if (!part_x_range(&plan->parts[k], px, py))
            continue;
        if (kept != k)
            plan->parts[kept] = plan->parts[k];
        plan->xs.add(plan->parts[kept].x0, plan->parts[kept].x1);
        ++kept;
    }
    plan->count = kept;
    plan->width = plan->xs.merge();
    plan->kind = plan->width > 0 ? PixelPlan::Aimed : PixelPlan::Dark;
}

// The plan of the pixel last asked for on this thread (samples come pixel by pixel).
// Per thread, the plans of the pixel last asked for: one per lens its samples were forced through
// (overlap modelling interleaves a pixel's lenses sample by sample), or the one unforced; up to
// kCachedPlans, then the oldest is made again.
const int kCachedPlans = 16;
struct CachedPlans {
    bool valid = false;
    CameraKey key;
    int i = 0, j = 0;
    int count = 0, next = 0;
    struct Entry {
        bool forced;
        LensIndex lens;
        PixelPlan plan;
    };
    std::vector<Entry> entries = std::vector<Entry>(kCachedPlans);
};

} // namespace

namespace {

// The pixel's plan through `forced` (or its own lenses), from this thread's cache or made now.
const PixelPlan& cached_plan(const PlenopticCamera& m, int i, int j, const LensIndex* forced)
{
    static thread_local CachedPlans cache;
    const bool same_camera = cache.valid && key_is(cache.key, m);
    if (!(same_camera && cache.i == i && cache.j == j)) {
        if (!same_camera)
            cache.key = key_of(m);
        cache.valid = true;
        cache.i = i;
        cache.j = j;
        cache.count = cache.next = 0;
    }
    int found = -1;
    for (int k = 0; k < cache.count && found < 0; ++k) {
        const CachedPlans::Entry& e = cache.entries[size_t(k)];
        if (e.forced == (forced != nullptr) && (!forced || e.lens == *forced))
            found = k;
    }
    if (found < 0) {
        found = cache.next;
        cache.next = (cache.next + 1) % kCachedPlans;
        cache.count = std::max(cache.count, found + 1);
        CachedPlans::Entry& e = cache.entries[size_t(found)];
        e.forced = forced != nullptr;
        e.lens = forced ? *forced : LensIndex{0, 0};
        plan_pixel(m, i, j, forced, &e.plan);
    }
    return cache.entries[size_t(found)].plan;
}

} // namespace

bool aim_reaches_pixel(const PlenopticCamera& m, int i, int j, LensIndex lens)
{
    return cached_plan(m, i, j, &lens).kind != PixelPlan::Dark;
}

PixelAim aim_pixel(const PlenopticCamera& m, int i, int j, double pixel_u, double pixel_v, const LensIndex* forced)
{
    PixelAim out{i + pixel_u, j + pixel_v, 1, false, LensIndex{0, 0}, true};
    const PixelPlan& plan = cached_plan(m, i, j, forced);
    if (plan.kind == PixelPlan::Uniform)
        return out;
    if (plan.forced) {
        out.lens_forced = true;
        out.lens = plan.lens;
    }
    if (plan.kind == PixelPlan::Dark) {
        out.passed = false;  // no light reaches the pixel
        return out;
    }
    const double x = plan.xs.at(pixel_u, plan.width);
    // y: the union of the parts' chords at x (within the pixel's rows).
    Intervals ys;
    for (int k = 0; k < plan.count; ++k) {
        const LensPart& part = plan.parts[k];
        if (!(x >= part.x0 && x <= part.x1))
            continue;  // the part's chord is empty there
        double y0, y1;
        if (part_chord(part, x, plan.py, &y0, &y1, false) > 0)
            ys.add(y0, y1);
    }
    const double height = ys.merge();
    if (!(height > 0)) {
        out.passed = false;
        return out;
    }
    out.pu = i + x / plan.px;
    out.pv = j + ys.at(pixel_v, height) / plan.py;
    out.weight = plan.width * height / (plan.px * plan.py);
    return out;
}

namespace {

// The cell's point (u, v) uniformly, as sample_ray takes it; through `frame` when the caller keeps
// the lens's frame.
inline ArrayRay uniform_cell_ray(const MicrolensArray& array, const Vec3& p, LensIndex lens, const LensFrame* frame,
                                 double u, double v)
{
    return frame ? array.microlens->cell_ray_in(array, p, *frame, array.cell_point(u, v))
                 : array.microlens->sample_ray(array, p, lens, u, v);
}

} // namespace

ArrayRay aimed_cell_ray(const PlenopticCamera& m, const Vec3& p, LensIndex lens, double u, double v, double* weight)
{
    *weight = 1;
    const MicrolensArray& array = m.array;
    // The lenses last aimed at on this thread (a pixel's samples go through one lens, or with
    // overlap modelling through a few in turn).
    struct CachedLenses {
        CameraKey key;
        int count = 0, next = 0, last = 0;
        bool aimed[8];
        LensAim aim[8];
        LensFrame frame[8];  // framed: each lens's frame
    };
    static thread_local CachedLenses cache;
    // An ideal array filling its cells takes its lenses from the lattice (cell_ray's own path); the
    // others' frames are looked up once a lens here, not again for every sample.
    const bool framed = array.errors || array.aperture_scale != 1;
    if (!(cache.count > 0 && key_is(cache.key, m))) {
        cache.key = key_of(m);
        cache.count = cache.next = 0;
    }
    // The lens last asked for first (a pixel's samples mostly go through one lens).
    int found = cache.count > 0 && cache.aim[cache.last].lens == lens ? cache.last : -1;
    for (int k = 0; k < cache.count && found < 0; ++k)
        if (cache.aim[k].lens == lens)
            found = k;
    if (found < 0) {
        found = cache.next;
        cache.next = (cache.next + 1) % 8;
        cache.count = std::max(cache.count, found + 1);
        cache.aimed[found] = lens_aim(m, lens, &cache.aim[found]);
        cache.aim[found].lens = lens;
        if (framed)
            cache.frame[found] = array.frame(lens);
    }
    cache.last = found;
    const LensFrame* frame = framed ? &cache.frame[found] : nullptr;
    if (!cache.aimed[found])
        return uniform_cell_ray(array, p, lens, frame, u, v);
    const LensAim& a = cache.aim[found];
    const Vec3 s = array.to_local(p);
    if (!(a.z - lens_frame_point(a, s).z > 0))
        return uniform_cell_ray(array, p, lens, frame, u, v);
    AimDisc discs[1 + LensAim::kMaxCuts];
    const int count = cell_discs(a, s, discs);
    bool whole = true;
    for (int k = 0; k < count && whole; ++k)
        whole = std::sqrt(discs[k].centre.x * discs[k].centre.x + discs[k].centre.y * discs[k].centre.y) +
                    a.circumradius <=
                discs[k].radius;
    if (whole)
        return uniform_cell_ray(array, p, lens, frame, u, v);  // the whole cell may pass
    // The cell's part in the discs: x uniform over its exact x range, y over the cell's height and
    // the discs' chords at x.
    const ArrayRay none{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}};
    double lo, hi;
    if (!cell_x_range(a, discs, count, &lo, &hi))
        return none;
    const double x = lo + u * (hi - lo);
    const double half = cell_half_height(a.grid, a.pitch, x);
    double y0 = -half, y1 = half;
    for (int k = 0; k < count; ++k) {
        const AimDisc& d = discs[k];
        const double t = (x - d.centre.x) / d.radius;
        const double c = d.radius * std::sqrt(t * t < 1 ? 1 - t * t : 0);
        y0 = std::max(y0, d.centre.y - c);
        y1 = std::min(y1, d.centre.y + c);
    }
    if (!(y1 > y0))
        return none;
    const double area = a.grid == GridType::Hexagonal ? 0.5 * kSqrt3 * a.pitch * a.pitch : a.pitch * a.pitch;
    *weight = (hi - lo) * (y1 - y0) / area;
    const Vec2 offset{x, y0 + v * (y1 - y0)};
    return frame ? array.microlens->cell_ray_in(array, p, *frame, offset) : array.microlens->cell_ray(array, p, lens, offset);
}

} // namespace plenoptic
