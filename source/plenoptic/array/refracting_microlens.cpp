// SPDX-License-Identifier: AGPL-3.0-or-later
// Refracting microlenses: the exact trace through a plano-convex cap on its substrate (see the
// header for the frame and the shape).

#include "plenoptic/array/refracting_microlens.h"

#include <cmath>
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
    // plane), the line from p through it traced through the lens, in the lens's own frame (its
    // actual centre and axis, array/microlens_array.h: LensFrame; a focal-length error scales the
    // cap's radius). The ray is returned from where its line in the scene-side air crosses the
    // lens's plane (nothing lies between that point and where it leaves the glass), so that users
    // that take rays to leave from the array's plane (the pupil bounds) hold for it; `sampled` is
    // the cell point.
    ArrayRay sample_ray(const MicrolensArray& array, const Vec3& p, LensIndex lens, double u, double v) const override
    {
        const LensFrame frame = array.frame(lens);
        const Vec2 offset = array.cell_point(u, v);
        const Vec3 h0{offset.x, offset.y, 0};
        const Vec3 d = h0 - to_lens(frame, array.to_local(p));
        const RefractingPath path = trace_to_scene(shape_of(frame), h0, d);
        if (!path.passed || !in_cell(array, lens, frame, path.sensor_face) || !in_cell(array, lens, frame, path.scene_face))
            return no_ray();
        const Vec3 dir = path.scene_side_dir;
        const Vec3 origin = path.scene_face - (path.scene_face.z / dir.z) * dir;
        return ArrayRay{array.to_optics(from_lens_point(frame, origin)), mul(array.pose.rotation, from_lens(frame, dir)),
                        true, array.to_optics(from_lens_point(frame, h0))};
    }

    // Refused at parse time with a pinhole main lens (camera/params.cpp): there is no closed form.
    ArrayRay ray_through(const MicrolensArray&, const Vec3&, LensIndex, Vec3, bool) const override { return no_ray(); }

    // The light's incoming line through h, traced through the lens; the ray is returned from where
    // it leaves the lens's sensor-side face.
    ArrayRay towards_sensor(const MicrolensArray& array, LensIndex lens, Vec3 h, Vec3 direction) const override
    {
        const LensFrame frame = array.frame(lens);
        const Vec3 w = to_lens_direction(frame, mul_transposed(array.pose.rotation, direction));
        if (!(w.z < 0))
            return no_ray();
        const RefractingPath path = trace_to_sensor(shape_of(frame), to_lens(frame, array.to_local(h)), -w);
        if (!path.passed || !in_cell(array, lens, frame, path.sensor_face) || !in_cell(array, lens, frame, path.scene_face))
            return no_ray();
        const Vec3 leave = array.to_optics(from_lens_point(frame, path.sensor_face));
        return ArrayRay{leave, mul(array.pose.rotation, from_lens(frame, -path.sensor_side_dir)), true, leave};
    }

    const RefractingShape& shape() const { return shape_; }

private:
    // The lens's frame: array-local points and directions to it and back.
    static Vec3 to_lens(const LensFrame& frame, Vec3 local)
    {
        const Vec3 rel = local - frame.centre;
        return frame.tilted ? mul_transposed(frame.axes, rel) : rel;
    }
    static Vec3 to_lens_direction(const LensFrame& frame, Vec3 v) { return frame.tilted ? mul_transposed(frame.axes, v) : v; }
    static Vec3 from_lens(const LensFrame& frame, Vec3 v) { return frame.tilted ? mul(frame.axes, v) : v; }
    static Vec3 from_lens_point(const LensFrame& frame, Vec3 q) { return frame.centre + from_lens(frame, q); }
    // Whether a point of the lens (its frame) lies in the lens's cell.
    static bool in_cell(const MicrolensArray& array, LensIndex lens, const LensFrame& frame, Vec3 q)
    {
        const Vec3 local = from_lens_point(frame, q);
        return array.nearest(local.x, local.y) == lens;
    }
    // The shape of a lens whose focal length has an error: its cap's radius scaled with it.
    RefractingShape shape_of(const LensFrame& frame) const
    {
        RefractingShape shape = shape_;
        if (frame.focal_mm != shape_.focal_length_mm())
            shape.radius_mm = frame.focal_mm * (shape_.ior - 1);
        return shape;
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

} // namespace plenoptic
