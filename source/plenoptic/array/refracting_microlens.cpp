// SPDX-License-Identifier: AGPL-3.0-or-later
// Refracting microlenses: the exact trace through a plano-convex cap on its substrate (see the
// header for the frame and the shape).

#include "plenoptic/array/refracting_microlens.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "plenoptic/array/microlens_array.h"

namespace plenoptic {

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

RefractingPath no_path() { return RefractingPath{false, Vec3{0, 0, 0}, Vec3{0, 0, 0}, Vec3{0, 0, 0}, Vec3{0, 0, 0}}; }

// Where the cap's surface is: its vertex's z and the side its sag grows towards (-1: the surface
// falls from the vertex towards the sensor, the curved side facing the scene).
double vertex_z(const RefractingShape& s) { return s.curved_towards_scene ? s.thickness_mm() : 0.0; }
double sag_sign(const RefractingShape& s) { return s.curved_towards_scene ? -1.0 : 1.0; }

// The parameters t of the line P + t D where it meets the cap's surface, on the sheet of the conic
// through the vertex (sag w >= 0 and (1 + k) c w <= 1), in increasing order; returns how many (0 to 2).
// The surface: c (x^2 + y^2 + (1 + k) w^2) - 2 w = 0 with w = sign (z - z_vertex).
int cap_hits(const RefractingShape& s, Vec3 P, Vec3 D, double t[2])
{
    const double c = 1 / s.radius_mm, k1 = 1 + s.conic, sign = sag_sign(s);
    const double w0 = sign * (P.z - vertex_z(s)), wd = sign * D.z;
    const double A = c * (D.x * D.x + D.y * D.y + k1 * wd * wd);
    const double B = 2 * c * (P.x * D.x + P.y * D.y + k1 * w0 * wd) - 2 * wd;
    const double C = c * (P.x * P.x + P.y * P.y + k1 * w0 * w0) - 2 * w0;
    double roots[2];
    int count = 0;
    const double scale = std::fabs(B) + std::sqrt(std::fabs(A * C));
    if (std::fabs(A) <= 1e-14 * scale) {
        if (B != 0)
            roots[count++] = -C / B;
    } else {
        const double disc = B * B - 4 * A * C;
        if (!(disc >= 0))
            return 0;
        const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
        roots[count++] = q / A;
        if (q != 0)
            roots[count++] = C / q;
    }
    int valid = 0;
    const double tolerance = 1e-12 * s.radius_mm;
    for (int i = 0; i < count; ++i) {
        const double w = w0 + roots[i] * wd;
        if (std::isfinite(roots[i]) && w >= -tolerance && k1 * c * w <= 1 + 1e-12)
            t[valid++] = roots[i];
    }
    if (valid == 2 && t[0] > t[1]) {
        const double swap = t[0];
        t[0] = t[1];
        t[1] = swap;
    }
    return valid;
}

// The cap's unit normal at its point q (either orientation).
Vec3 cap_normal(const RefractingShape& s, Vec3 q)
{
    const double c = 1 / s.radius_mm, sign = sag_sign(s);
    const double w = sign * (q.z - vertex_z(s));
    return normalized(Vec3{c * q.x, c * q.y, sign * (c * (1 + s.conic) * w - 1)});
}

// Snell's law in vector form: unit direction d crossing a surface of unit normal n (either
// orientation) from index n1 into n2, eta = n1 / n2. False on total internal reflection.
bool refract(Vec3 d, Vec3 n, double eta, Vec3* out)
{
    double cosi = -dot(d, n);
    if (cosi < 0) {
        n = -n;
        cosi = -cosi;
    }
    const double k = 1 - eta * eta * (1 - cosi * cosi);
    if (!(k >= 0))
        return false;
    *out = eta * d + (eta * cosi - std::sqrt(k)) * n;
    return true;
}

const Vec3 kAxis{0, 0, 1};

} // namespace

double RefractingShape::sag(double r2) const
{
    const double c = 1 / radius_mm;
    const double root = 1 - (1 + conic) * c * c * r2;
    if (!(root >= 0))
        return kNaN;
    return c * r2 / (1 + std::sqrt(root));
}

double RefractingShape::front_principal_z() const
{
    return curved_towards_scene ? thickness_mm() : thickness_mm() - thickness_mm() / ior;
}

double RefractingShape::rear_principal_z() const { return curved_towards_scene ? thickness_mm() / ior : 0.0; }

RefractingPath trace_to_scene(const RefractingShape& s, Vec3 h0, Vec3 d)
{
    if (!(d.z > 0))
        return no_path();
    const Vec3 u = normalized(d);
    const double n = s.ior, L = s.thickness_mm();
    RefractingPath path = no_path();
    path.sensor_side_dir = u;
    double t[2];
    if (s.curved_towards_scene) {
        // Into the flat back at h0, up through the glass to the cap, out into the air.
        Vec3 inside;
        if (!refract(u, kAxis, 1 / n, &inside))
            return no_path();
        const int hits = cap_hits(s, h0, inside, t);
        int i = 0;
        while (i < hits && !(t[i] > 0))
            ++i;
        if (i == hits)
            return no_path();
        const Vec3 q = h0 + t[i] * inside;
        Vec3 out;
        if (!refract(inside, cap_normal(s, q), n, &out) || !(out.z > 0))
            return no_path();
        path.sensor_face = h0;
        path.scene_face = q;
        path.scene_side_dir = out;
    } else {
        // On to the cap (the first point of its surface on the line), into the glass, up to the flat
        // front, out into the air.
        const int hits = cap_hits(s, h0, u, t);
        if (hits == 0)
            return no_path();
        const Vec3 q = h0 + t[0] * u;
        Vec3 inside, out;
        if (!refract(u, cap_normal(s, q), 1 / n, &inside) || !(inside.z > 0))
            return no_path();
        const Vec3 front = q + ((L - q.z) / inside.z) * inside;
        if (!refract(inside, kAxis, n, &out))
            return no_path();
        path.sensor_face = q;
        path.scene_face = front;
        path.scene_side_dir = out;
    }
    path.passed = true;
    return path;
}

RefractingPath trace_to_sensor(const RefractingShape& s, Vec3 h, Vec3 d)
{
    if (!(d.z > 0))
        return no_path();
    const Vec3 v = normalized(d);
    const Vec3 a = -v;  // the direction of travel
    const double n = s.ior, L = s.thickness_mm();
    RefractingPath path = no_path();
    path.scene_side_dir = v;
    double t[2];
    if (s.curved_towards_scene) {
        // The light meets the cap where its line does first coming from the scene (the larger t
        // along v), refracts into the glass, down to the flat back, out.
        const int hits = cap_hits(s, h, v, t);
        if (hits == 0 || !(t[hits - 1] > 0))
            return no_path();
        const Vec3 q = h + t[hits - 1] * v;
        Vec3 inside, out;
        if (!refract(a, cap_normal(s, q), 1 / n, &inside) || !(inside.z < 0))
            return no_path();
        const Vec3 back = q + (-q.z / inside.z) * inside;
        if (!refract(inside, kAxis, n, &out))
            return no_path();
        path.scene_face = q;
        path.sensor_face = back;
        path.sensor_side_dir = -out;
    } else {
        // The flat front, into the glass, down to the cap (the first point of its surface on the
        // way down), out.
        const Vec3 front = h + ((L - h.z) / v.z) * v;
        Vec3 inside, out;
        if (!refract(a, kAxis, 1 / n, &inside) || !(inside.z < 0))
            return no_path();
        const int hits = cap_hits(s, front, inside, t);
        int i = 0;
        while (i < hits && !(t[i] > 0))
            ++i;
        if (i == hits)
            return no_path();
        const Vec3 q = front + t[i] * inside;
        if (!refract(inside, cap_normal(s, q), n, &out) || !(out.z < 0))
            return no_path();
        path.scene_face = front;
        path.sensor_face = q;
        path.sensor_side_dir = -out;
    }
    path.passed = true;
    return path;
}

namespace {

ArrayRay no_ray() { return ArrayRay{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}}; }

// Most cells a path crosses inside the array (its entry lens's included) before it meets a surface;
// one that would cross more travels nearly along the array and is blocked.
const int kMaxCells = 8;

// Where a path inside the array is: in the glass, or in the air between the caps and the sensor
// (caps facing the sensor only).
enum class Medium { Glass, AirUnderCaps };

// The surface a path meets: the lens whose surface it is, the point and the direction of travel
// (unit) in that lens's frame, and whether it is the cap or the flat face.
struct SurfaceHit {
    LensIndex lens;
    LensFrame frame;
    RefractingShape shape;
    Vec3 q;
    Vec3 dir;
    bool on_cap;
};

// The lens's frame: array-local points and directions to it and back.
Vec3 to_lens(const LensFrame& frame, Vec3 local)
{
    const Vec3 rel = local - frame.centre;
    return frame.tilted ? mul_transposed(frame.axes, rel) : rel;
}
Vec3 to_lens_direction(const LensFrame& frame, Vec3 v) { return frame.tilted ? mul_transposed(frame.axes, v) : v; }
Vec3 from_lens(const LensFrame& frame, Vec3 v) { return frame.tilted ? mul(frame.axes, v) : v; }
Vec3 from_lens_point(const LensFrame& frame, Vec3 q) { return frame.centre + from_lens(frame, q); }

// Whether a point of a lens (its frame) lies in the lens's cell.
bool in_cell(const MicrolensArray& array, LensIndex lens, const LensFrame& frame, Vec3 q)
{
    const Vec3 local = from_lens_point(frame, q);
    return array.nearest(local.x, local.y) == lens;
}

// Whether the point P of a lens's column (its frame) lies in the medium there: the glass between
// the flat face and the cap, or the air under a cap facing the sensor.
bool in_medium(const RefractingShape& s, Medium medium, Vec3 P)
{
    const double tolerance = 1e-9 * s.thickness_mm();
    const double sag = s.sag(P.x * P.x + P.y * P.y);
    if (!(sag == sag))
        return false;
    if (medium == Medium::AirUnderCaps)
        return P.z <= sag + tolerance;
    if (s.curved_towards_scene)
        return P.z >= -tolerance && P.z <= s.thickness_mm() - sag + tolerance;
    return P.z >= sag - tolerance && P.z <= s.thickness_mm() + tolerance;
}

// The first surface of a lens ahead of P along unit D (its frame) in the medium: in the glass the
// cap or the flat face (not the point P itself, where the path may just have entered), under a cap
// the cap. Infinity when there is none.
double surface_ahead(const RefractingShape& s, Medium medium, Vec3 P, Vec3 D, bool* on_cap)
{
    double t[2];
    const int hits = cap_hits(s, P, D, t);
    const double tolerance = 1e-9 * s.thickness_mm();
    double best = std::numeric_limits<double>::infinity();
    *on_cap = true;
    if (medium == Medium::AirUnderCaps) {
        for (int i = 0; i < hits; ++i)
            if (t[i] >= -tolerance)
                return t[i];
        return best;
    }
    for (int i = 0; i < hits; ++i) {
        if (t[i] > tolerance) {
            best = t[i];
            break;
        }
    }
    const double flat_z = s.curved_towards_scene ? 0.0 : s.thickness_mm();
    if (D.z != 0) {
        const double t_flat = (flat_z - P.z) / D.z;
        if (t_flat > tolerance && t_flat < best) {
            best = t_flat;
            *on_cap = false;
        }
    }
    return best;
}

// Where the line X + t V (array-local) leaves the cell of `lens` ahead (t >= 0): the first
// bisector with a neighbour's actual centre that it crosses (the cells are those of
// MicrolensArray::nearest, whose neighbours these are); `next` is that neighbour.
double cell_exit(const MicrolensArray& array, LensIndex lens, Vec3 X, Vec3 V, LensIndex* next)
{
    const Vec2 c = array.centre_local(lens);
    double best = std::numeric_limits<double>::infinity();
    LensIndex adjacent[8];
    const int n_adjacent = adjacent_lenses(array.grid, lens, adjacent);
    for (int q = 0; q < n_adjacent; ++q) {
        const LensIndex n = adjacent[q];
        const Vec2 cn = array.centre_local(n);
        const double ex = cn.x - c.x, ey = cn.y - c.y;
        const double along = V.x * ex + V.y * ey;
        if (!(along > 0))
            continue;
        const double t = ((0.5 * (c.x + cn.x) - X.x) * ex + (0.5 * (c.y + cn.y) - X.y) * ey) / along;
        if (t < best) {
            best = t;
            *next = n;
        }
    }
    return std::max(best, 0.0);
}

class RefractingMicrolens : public Microlens {
public:
    explicit RefractingMicrolens(const RefractingShape& shape) : shape_(shape) {}

    const char* kind_name() const override { return "refracting"; }
    bool forms_image() const override { return true; }
    bool first_order_exact() const override { return false; }
    double thickness_mm() const override { return shape_.thickness_mm(); }
    double focal_length_mm(int) const override { return shape_.focal_length_mm(); }
    // Dispersion: the glass's index at the wavelength, n' = 1 + (n - 1) factor, which scales the
    // lens's power (n - 1) / R by the factor.
    std::shared_ptr<const Microlens> with_power_scaled(double factor) const override
    {
        RefractingShape shape = shape_;
        shape.ior = 1 + (shape_.ior - 1) * factor;
        return std::make_shared<RefractingMicrolens>(shape);
    }

    // The cell point (u, v) in the lens's plane (the face nearest the sensor, or the caps' vertex
    // plane), the line from p through it traced through the array, starting in the lens's own frame
    // (its actual centre and axis, array/microlens_array.h: LensFrame; a focal-length error scales
    // the cap's radius). The lines from p are shared out among the lenses by where they cross that
    // plane. Without baffles a path that leaves the lens's cell before it meets a surface goes on
    // in the neighbour's column (in the glass, or in the air under caps facing the sensor) and
    // leaves through whatever surface of the neighbour's it meets (walk); with baffles it is
    // blocked. The ray is returned from where its line in the scene-side air crosses the plane of
    // the lens it leaves (nothing lies between that point and where it leaves the glass), so that
    // users that take rays to leave from the array's plane (the pupil bounds) hold for it;
    // `sampled` is the cell point.
    ArrayRay sample_ray(const MicrolensArray& array, const Vec3& p, LensIndex lens, double u, double v) const override
    {
        return trace_sample(array, p, lens, u, v, nullptr);
    }

    // sample_ray's path; `crossed` (if given) is set when the path goes on in a neighbour's column.
    ArrayRay trace_sample(const MicrolensArray& array, const Vec3& p, LensIndex lens, double u, double v,
                          bool* crossed) const
    {
        const LensFrame frame = array.frame(lens);
        const Vec2 offset = array.cell_point(u, v);
        const Vec3 h0{offset.x, offset.y, 0};
        const Vec3 d = h0 - to_lens(frame, array.to_local(p));
        if (!(d.z > 0))
            return no_ray();
        // With errors the cell point (of the lattice's cell shape about the actual centre) may lie
        // in a neighbour's cell, whose own samples cover that line.
        if (array.errors && !in_cell(array, lens, frame, h0))
            return no_ray();
        const Vec3 start = from_lens_point(frame, h0);
        const Vec3 air = normalized(d);
        const double n = shape_.ior;
        SurfaceHit leave;
        Vec3 out;
        if (shape_.curved_towards_scene) {
            // Into the flat back at h0, through the glass to a cap, out into the air.
            Vec3 inside;
            if (!refract(air, kAxis, 1 / n, &inside))
                return no_ray();
            if (!walk(array, Medium::Glass, lens, frame, start, from_lens(frame, inside), &leave, crossed) ||
                !leave.on_cap)
                return no_ray();
            if (!refract(leave.dir, cap_normal(leave.shape, leave.q), n, &out) || !(out.z > 0))
                return no_ray();
        } else {
            // Up through the air to a cap, into the glass, up to the flat front, out.
            SurfaceHit cap;
            if (!walk(array, Medium::AirUnderCaps, lens, frame, start, from_lens(frame, air), &cap, crossed))
                return no_ray();
            Vec3 inside;
            if (!refract(cap.dir, cap_normal(cap.shape, cap.q), 1 / n, &inside) || !(inside.z > 0))
                return no_ray();
            if (!walk(array, Medium::Glass, cap.lens, cap.frame, from_lens_point(cap.frame, cap.q),
                      from_lens(cap.frame, inside), &leave, crossed) ||
                leave.on_cap)
                return no_ray();
            if (!refract(leave.dir, kAxis, n, &out))
                return no_ray();
        }
        const Vec3 origin = leave.q - (leave.q.z / out.z) * out;
        return ArrayRay{array.to_optics(from_lens_point(leave.frame, origin)),
                        mul(array.pose.rotation, from_lens(leave.frame, out)), true, array.to_optics(start)};
    }

    // Refused at parse time with a pinhole main lens (camera/params.cpp): there is no closed form.
    ArrayRay ray_through(const MicrolensArray&, const Vec3&, LensIndex, Vec3, bool) const override { return no_ray(); }

    // The light's incoming line through h meets the lens's face nearest the scene (its cap, or its
    // flat front) inside the lens's cell: traced on through the array (as sample_ray, a path that
    // leaves the cell in the glass goes on in the neighbour's unless there are baffles); the ray
    // is returned from where it leaves the face nearest the sensor.
    ArrayRay towards_sensor(const MicrolensArray& array, LensIndex lens, Vec3 h, Vec3 direction) const override
    {
        const LensFrame frame = array.frame(lens);
        const RefractingShape shape = shape_of(frame);
        const Vec3 w = to_lens_direction(frame, mul_transposed(array.pose.rotation, direction));
        if (!(w.z < 0))
            return no_ray();
        const Vec3 hl = to_lens(frame, array.to_local(h));
        const Vec3 v = normalized(-w);
        const Vec3 a = -v;  // the direction of travel
        const double n = shape.ior;
        SurfaceHit leave;
        Vec3 out;
        if (shape.curved_towards_scene) {
            // The cap where the line meets it first coming from the scene, into the glass, down to
            // a flat back, out.
            double t[2];
            const int hits = cap_hits(shape, hl, v, t);
            if (hits == 0 || !(t[hits - 1] > 0))
                return no_ray();
            const Vec3 q = hl + t[hits - 1] * v;
            Vec3 inside;
            if (!in_cell(array, lens, frame, q) || !refract(a, cap_normal(shape, q), 1 / n, &inside) || !(inside.z < 0))
                return no_ray();
            if (!walk(array, Medium::Glass, lens, frame, from_lens_point(frame, q), from_lens(frame, inside), &leave) ||
                leave.on_cap)
                return no_ray();
            if (!refract(leave.dir, kAxis, n, &out))
                return no_ray();
        } else {
            // The flat front, into the glass, down to a cap, out.
            const Vec3 front = hl + ((shape.thickness_mm() - hl.z) / v.z) * v;
            Vec3 inside;
            if (!in_cell(array, lens, frame, front) || !refract(a, kAxis, 1 / n, &inside) || !(inside.z < 0))
                return no_ray();
            if (!walk(array, Medium::Glass, lens, frame, from_lens_point(frame, front), from_lens(frame, inside),
                      &leave) ||
                !leave.on_cap)
                return no_ray();
            if (!refract(leave.dir, cap_normal(leave.shape, leave.q), n, &out) || !(out.z < 0))
                return no_ray();
        }
        const Vec3 at = array.to_optics(from_lens_point(leave.frame, leave.q));
        return ArrayRay{at, mul(array.pose.rotation, from_lens(leave.frame, out)), true, at};
    }

    const RefractingShape& shape() const { return shape_; }

private:
    // The shape of a lens whose focal length has an error: its cap's radius scaled with it.
    RefractingShape shape_of(const LensFrame& frame) const
    {
        RefractingShape shape = shape_;
        if (frame.focal_mm != shape_.focal_length_mm())
            shape.radius_mm = frame.focal_mm * (shape_.ior - 1);
        return shape;
    }

    // A path in `medium` from the array-local point X (in lens `lens`'s column, whose frame is
    // given) along the unit direction V, to the first surface it meets. While that surface's point
    // lies outside the current lens's cell the path leaves the cell first: without baffles it goes
    // on in the neighbour's column, in the neighbour's frame (where lenses with errors do not meet,
    // a path that steps out of the medium is blocked); with baffles it is blocked, as after
    // kMaxCells cells.
    bool walk(const MicrolensArray& array, Medium medium, LensIndex lens, LensFrame frame, Vec3 X, Vec3 V,
              SurfaceHit* hit, bool* crossed = nullptr) const
    {
        for (int cells = 0; cells < kMaxCells; ++cells) {
            if (cells > 0)
                frame = array.frame(lens);
            const RefractingShape shape = shape_of(frame);
            const Vec3 P = to_lens(frame, X), D = to_lens_direction(frame, V);
            if (cells > 0 && !in_medium(shape, medium, P))
                return false;
            bool on_cap;
            const double t = surface_ahead(shape, medium, P, D, &on_cap);
            const bool ahead = t < std::numeric_limits<double>::infinity();
            const Vec3 q = P + (ahead ? t : 0.0) * D;
            LensIndex next = lens;
            // No surface of this lens ahead (the line misses its cap), or the surface's point lies
            // outside the cell: the path leaves the cell first.
            if (!ahead || !in_cell(array, lens, frame, q)) {
                if (array.baffles)
                    return false;
                const double exit = cell_exit(array, lens, X, V, &next);
                if (exit < t) {
                    X = X + exit * V;
                    lens = next;
                    if (crossed)
                        *crossed = true;
                    continue;
                }
                if (!ahead)
                    return false;
                // On the cell's border within rounding: the surface is this lens's.
            }
            *hit = SurfaceHit{lens, frame, shape, q, D, on_cap};
            return true;
        }
        return false;
    }

    RefractingShape shape_;
};

} // namespace

std::shared_ptr<const Microlens> make_refracting_microlens(const RefractingShape& shape)
{
    return std::make_shared<RefractingMicrolens>(shape);
}

const RefractingShape* refracting_shape(const Microlens& microlens)
{
    const RefractingMicrolens* refracting = dynamic_cast<const RefractingMicrolens*>(&microlens);
    return refracting ? &refracting->shape() : nullptr;
}

bool refracting_sample_crosses_cells(const MicrolensArray& array, const Vec3& p, LensIndex lens, double u, double v)
{
    const RefractingMicrolens* refracting = dynamic_cast<const RefractingMicrolens*>(array.microlens.get());
    if (!refracting)
        return false;
    bool crossed = false;
    return refracting->trace_sample(array, p, lens, u, v, &crossed).passed && crossed;
}

} // namespace plenoptic
