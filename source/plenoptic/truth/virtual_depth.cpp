// SPDX-License-Identifier: AGPL-3.0-or-later
// Virtual depth of scene points and of a depth map's pixels (see truth/virtual_depth.h).

#include "plenoptic/truth/virtual_depth.h"

#include <cmath>
#include <limits>

#include "plenoptic/lens/main_lens.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/camera/rays.h"

namespace plenoptic {

bool is_focused_camera(const PlenopticCamera& m)
{
    if (!m.array.present() || !m.array.microlens->forms_image() || !m.lens || !m.lens->forms_image())
        return false;
    const double d = effective_array_distance_mm(m);
    for (int t = 0; t < m.array.lens_type_count; ++t)
        if (std::fabs(m.array.microlens->focal_length_mm(t) - d) > 1e-9 * d)
            return true;
    return false;
}

double virtual_depth(const PlenopticCamera& m, Vec3 point)
{
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (!m.lens || !m.lens->forms_image() || m.array.grid == GridType::None)
        return nan;
    const HomogeneousPoint image = m.lens->paraxial_image(point);
    if (!(image.w != 0))
        return nan;
    const Vec3 x = (1 / image.w) * image.xyz;
    const double a = dot(m.array.pose.normal, x - m.array.pose.centre_mm);
    const double v = -a / effective_array_distance_mm(m);
    return std::isfinite(v) ? v : nan;
}

float pixel_virtual_depth(const PlenopticCamera& m, int i, int j, float distance_units)
{
    if (!(distance_units >= 0))
        return std::numeric_limits<float>::quiet_NaN();
    const OpticsRay ray = m.chief_ray(i, j);
    const Vec3 origin{ray.origin_mm.x, ray.origin_mm.y, ray.origin_mm.z};
    const Vec3 dir{ray.dir.x, ray.dir.y, ray.dir.z};
    // At infinity: a point as far as a length can be (1e12 mm) images within 1e-10 of the
    // focal plane, below a float's resolution of v.
    const double along = std::isinf(distance_units) ? kMaxLengthMm : double(distance_units) * m.mm_per_unit;
    const Vec3 point = origin + along * dir;
    if (m.array.errors && m.lens && m.lens->forms_image()) {
        // A lens displaced along the normal: v from its own plane, v = -a_L / d_L.
        const OwnLens own = own_lens(m, m.sensor.point(i + 0.5, j + 0.5));
        const HomogeneousPoint image = m.lens->paraxial_image(point);
        if (own.found && image.w != 0) {
            const Vec3 c = m.array.centre_mm(own.lens);
            const Vec3 x = (1 / image.w) * image.xyz;
            const double v = -dot(m.array.pose.normal, x - c) / dot(m.array.pose.normal, c - Vec3{0, 0, m.sensor.z_mm});
            return std::isfinite(v) ? float(v) : std::numeric_limits<float>::quiet_NaN();
        }
    }
    return float(virtual_depth(m, point));
}

} // namespace plenoptic
