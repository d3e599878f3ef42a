// SPDX-License-Identifier: AGPL-3.0-or-later
// libpleno's blur-aware point model (see truth/blur.h).

#include "plenoptic/truth/blur.h"

#include <cmath>
#include <limits>

#include "plenoptic/lens/main_lens.h"
#include "plenoptic/camera/rays.h"

namespace plenoptic {

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The main lens's own blur on the sensor (no array).
double main_lens_blur_px(const PlenopticCamera& m, Vec3 point)
{
    if (!m.lens || !m.lens->forms_image())
        return 0;
    const HomogeneousPoint image = m.lens->paraxial_image(point);
    const Vec3 pupil = m.lens->exit_pupil_centre();
    const double s = pupil.z - m.sensor.z_mm;  // sensor behind the exit pupil
    if (image.w == 0)
        return kNaN;
    const double b = pupil.z - image.xyz.z / image.w;  // image behind the exit pupil
    if (!(b != 0))
        return kNaN;
    return m.lens->exit_pupil_radius() * (s / b - 1) / m.sensor.pixel_size_mm[0];
}

} // namespace

double blur_radius_px(const PlenopticCamera& m, Vec3 point, LensIndex lens)
{
    if (m.array.grid == GridType::None)
        return main_lens_blur_px(m, point);
    if (!m.array.microlens->forms_image() || (m.lens && !m.lens->forms_image()))
        return 0;
    const Vec3 c = lens_centre_mm(m, lens);
    double inverse_a = 0;  // 1/a; 0 for an image at infinity
    if (!m.lens) {
        const double a = dot(m.array.pose.normal, point - c);
        inverse_a = 1 / a;
    } else {
        const HomogeneousPoint image = m.lens->paraxial_image(point);
        // a = n . (X / w - c) = (n . X - w n . c) / w, so 1/a = w / (n . X - w n . c).
        inverse_a = image.w / (dot(m.array.pose.normal, image.xyz) - image.w * dot(m.array.pose.normal, c));
    }
    const double f = m.array.focal_length_mm(lens);
    const double d = c.z - m.sensor.z_mm;
    // The lens's aperture: a disc of diameter p (the BAP model), scaled with the lens part of the
    // cell (fill_factor).
    const double r = 0.5 * m.array.pitch_mm * m.array.aperture_scale * d * (1 / f - inverse_a - 1 / d);
    return std::isfinite(r) ? r / m.sensor.pixel_size_mm[0] : kNaN;
}

} // namespace plenoptic
