// SPDX-License-Identifier: AGPL-3.0-or-later
// The two kinds of microlens: pinholes and ideal thin lenses.

#include "plenoptic/array/microlens.h"

#include <cmath>
#include <limits>

#include "plenoptic/array/microlens_array.h"

namespace plenoptic {

std::vector<double> Microlens::focal_lengths_mm() const
{
    std::vector<double> out;
    if (forms_image())
        for (int t = 0; t < type_count(); ++t)
            out.push_back(focal_length_mm(t));
    return out;
}

namespace {

ArrayRay no_ray() { return ArrayRay{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}}; }

// A pinhole at each lens centre: every ray through it goes straight on.
class PinholeMicrolens : public Microlens {
public:
    const char* kind_name() const override { return "pinhole"; }
    bool forms_image() const override { return false; }
    double focal_length_mm(int) const override { return std::numeric_limits<double>::quiet_NaN(); }

    ArrayRay sample_ray(const MicrolensArray& array, const Vec3& p, LensIndex lens, double, double) const override
    {
        const Vec3 leave = array.to_optics(array.centre_local3(lens));
        const Vec3 direction = leave - p;
        if (!(dot(direction, array.pose.normal) > 0))
            return no_ray();  // the sensor point is not behind the array
        return ArrayRay{leave, direction, true, leave};
    }

    ArrayRay ray_through(const MicrolensArray&, const Vec3&, LensIndex, Vec3, bool) const override { return no_ray(); }

    ArrayRay towards_sensor(const MicrolensArray&, LensIndex, Vec3 h, Vec3 direction) const override
    {
        return ArrayRay{h, direction, true, h};
    }
};

// Ideal thin lenses, refracting in the array's own frame: with the direction normalised to unit
// component along the normal, w' = w - (h - c) / f for a ray meeting the lens at h.
class ThinMicrolens final : public Microlens {
public:
    ThinMicrolens(const double* focal_mm, int type_count) : type_count_(type_count)
    {
        for (int t = 0; t < 3; ++t)
            focal_mm_[t] = focal_mm[t < type_count ? t : 0];
    }

    const char* kind_name() const override { return "thin_lens"; }
    bool forms_image() const override { return true; }
    int type_count() const override { return type_count_; }
    double focal_length_mm(int type) const override { return focal_mm_[type]; }
    std::shared_ptr<const Microlens> with_power_scaled(double factor) const override
    {
        double focal[3];
        for (int t = 0; t < 3; ++t)
            focal[t] = focal_mm_[t] / factor;
        return std::make_shared<ThinMicrolens>(focal, type_count_);
    }

    // A point of the lens's cell, uniform over it; refraction in the lens's own frame (the array's,
    // moved to the lens centre and turned to its axis). A point of the cell's gap (fill_factor)
    // passes light unbent, unless a mask blocks it.
    ArrayRay sample_ray(const MicrolensArray& array, const Vec3& p, LensIndex lens, double u, double v) const override
    {
        return cell_ray(array, p, lens, array.cell_point(u, v));
    }

    bool aims() const override { return true; }

    ArrayRay cell_ray(const MicrolensArray& array, const Vec3& p, LensIndex lens, Vec2 offset) const override
    {
        if (!array.errors && array.aperture_scale == 1) {
            // Ideal lenses filling their cells: the lattice centre, the type's focal length.
            const double f = focal_mm_[array.type_of(lens)];
            const Vec2 c = array.lattice_centre_local(lens);
            const Vec3 leave = array.to_optics(Vec3{c.x + offset.x, c.y + offset.y, 0});
            const Vec3 w = mul_transposed(array.pose.rotation, leave - p);
            if (!(w.z > 0))
                return no_ray();
            const Vec3 refracted{w.x / w.z - offset.x / f, w.y / w.z - offset.y / f, 1};
            return ArrayRay{leave, mul(array.pose.rotation, refracted), true, leave};
        }
        return cell_ray_in(array, p, array.frame(lens), offset);
    }

    ArrayRay cell_ray_in(const MicrolensArray& array, const Vec3& p, const LensFrame& frame, Vec2 offset) const override
    {
        const bool lens_part = array.in_aperture(offset);
        if (!lens_part && array.mask)
            return no_ray();
        const Vec3 in_plane{offset.x, offset.y, 0};
        const Vec3 leave = array.to_optics(frame.centre + (frame.tilted ? mul(frame.axes, in_plane) : in_plane));
        Vec3 w = mul_transposed(array.pose.rotation, leave - p);
        if (frame.tilted)
            w = mul_transposed(frame.axes, w);
        if (!(w.z > 0))
            return no_ray();
        const double f = frame.focal_mm;
        Vec3 refracted = lens_part ? Vec3{w.x / w.z - offset.x / f, w.y / w.z - offset.y / f, 1} : Vec3{w.x / w.z, w.y / w.z, 1};
        if (frame.tilted)
            refracted = mul(frame.axes, refracted);
        return ArrayRay{leave, mul(array.pose.rotation, refracted), true, leave};
    }

    // The lens images the target O to the homogeneous point I = (o, 1 - o_z/f) (lens-relative
    // coordinates); every ray from p aimed at I leaves the lens through O. No division by
    // (1 + D/d - D/f), so near-degenerate set-ups only block rays. In the lens's own frame; a point
    // of the cell's gap is not a point of the lens (fill_factor).
    ArrayRay ray_through(const MicrolensArray& array, const Vec3& p, LensIndex lens, Vec3 target, bool check_cell) const override
    {
        const LensFrame frame = array.frame(lens);
        const double f = frame.focal_mm;
        const Vec3 o_rel = to_lens(frame, array.to_local(target));
        const Vec3 p_rel = to_lens(frame, array.to_local(p));
        if (!(o_rel.z > 0) || !(p_rel.z < 0))
            return no_ray();
        const double w = 1 - o_rel.z / f;
        Vec3 along = o_rel - w * p_rel;  // direction of the line p -> I
        if (along.z < 0)
            along = -along;
        if (!(along.z > 0))
            return no_ray();
        const double t = -p_rel.z / along.z;
        const double hx = p_rel.x + t * along.x;
        const double hy = p_rel.y + t * along.y;
        if (check_cell) {
            const Vec3 h_local = frame.centre + from_lens(frame, Vec3{hx, hy, 0});
            if (array.nearest(h_local.x, h_local.y) != lens || !array.in_aperture(Vec2{hx, hy}))
                return no_ray();
        }
        const Vec3 local_out = from_lens(frame, Vec3{along.x / along.z - hx / f, along.y / along.z - hy / f, 1});
        return ArrayRay{target, mul(array.pose.rotation, local_out), true, target};
    }

    ArrayRay towards_sensor(const MicrolensArray& array, LensIndex lens, Vec3 h, Vec3 direction) const override
    {
        const LensFrame frame = array.frame(lens);
        Vec3 w = mul_transposed(array.pose.rotation, direction);
        if (frame.tilted)
            w = mul_transposed(frame.axes, w);
        if (!(w.z < 0))
            return no_ray();
        // Where the light meets the lens's plane, relative to its centre, in its own frame (h itself
        // when the lens lies in the array's plane: h is on it).
        Vec3 rel = array.to_local(h) - frame.centre;
        double to_plane = 0;
        if (frame.tilted || frame.centre.z != 0) {
            if (frame.tilted)
                rel = mul_transposed(frame.axes, rel);
            to_plane = rel.z / -w.z;
        }
        const double hx = rel.x + to_plane * w.x, hy = rel.y + to_plane * w.y;
        const bool lens_part = array.in_aperture(Vec2{hx, hy});
        if (!lens_part && array.mask)
            return no_ray();
        const double f = frame.focal_mm;
        const Vec3 out_local = from_lens(frame, lens_part ? Vec3{w.x / -w.z - hx / f, w.y / -w.z - hy / f, -1}
                                                          : Vec3{w.x / -w.z, w.y / -w.z, -1});
        const Vec3 at = to_plane == 0 ? h : array.to_optics(frame.centre + from_lens(frame, Vec3{hx, hy, 0}));
        return ArrayRay{at, mul(array.pose.rotation, out_local), true, at};
    }

private:
    // Array-local points (relative to the array's origin) to the lens's own frame and directions back.
    static Vec3 to_lens(const LensFrame& frame, Vec3 local)
    {
        const Vec3 rel = local - frame.centre;
        return frame.tilted ? mul_transposed(frame.axes, rel) : rel;
    }
    static Vec3 from_lens(const LensFrame& frame, Vec3 v) { return frame.tilted ? mul(frame.axes, v) : v; }

    int type_count_;
    double focal_mm_[3];
};

} // namespace

std::shared_ptr<const Microlens> make_pinhole_microlens() { return std::make_shared<PinholeMicrolens>(); }

std::shared_ptr<const Microlens> make_thin_microlens(const double* focal_mm, int type_count)
{
    return std::make_shared<ThinMicrolens>(focal_mm, type_count);
}

} // namespace plenoptic
