// SPDX-License-Identifier: AGPL-3.0-or-later
#include "plenoptic/camera/light_check.h"

#include <algorithm>
#include <cmath>

#include "plenoptic/camera/pixel.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/core/sampling.h"

namespace plenoptic {

namespace {

const int kSamplesPerPixel = 16;
const int kMaxPatchPixels = 64;

} // namespace

double lit_fraction_near_axis(const PlenopticCamera& camera)
{
    // A patch about three microimages (or, without an array, a few pixels) across, centred on
    // the pixel where the optical axis meets the sensor.
    int patch = 8;
    if (camera.array.grid != GridType::None) {
        const double pixel_mm = std::min(camera.sensor.pixel_size_mm[0], camera.sensor.pixel_size_mm[1]);
        const double across = 3 * camera.array.pitch_mm / pixel_mm;
        patch = int(std::min<double>(kMaxPatchPixels, std::max(8.0, std::ceil(across))));
    }
    // The camera taking a picture of just the patch.
    const PlenopticCamera model = with_film(camera, patch, patch);
    const Vec2 axis = model.sensor.principal_point_px();
    if (!std::isfinite(axis.x) || !std::isfinite(axis.y))
        return 0;
    const int i0 = int(std::floor(axis.x)) - patch / 2, j0 = int(std::floor(axis.y)) - patch / 2;
    long passing = 0, total = 0;
    for (int j = j0; j < j0 + patch; ++j)
        for (int i = i0; i < i0 + patch; ++i)
            for (int n = 0; n < kSamplesPerPixel; ++n, ++total) {
                const OpticsRay ray = generate_ray_unaimed(model, i, j, make_sample(i, j, n, kSamplesPerPixel));
                if (ray.passed)
                    ++passing;
            }
    return total > 0 ? double(passing) / total : 0;
}

std::string dark_image_warning(const PlenopticCamera& model)
{
    const double fraction = lit_fraction_near_axis(model);
    if (fraction >= kDarkImageFraction)
        return "";
    std::string message = "almost no light reaches the sensor: " + format_number(100 * fraction) +
                          " % of the camera's sample rays around the optical axis pass the apertures, so the "
                          "image will be " + (fraction > 0 ? "nearly black" : "black");
    if (model.lens)
        message += model.lens->dark_image_advice(model.distance_mm);
    return message;
}

bool PlenopticCamera::receives_light(int i, int j) const
{
    return pixel_receives_light(*this, i, j);
}

} // namespace plenoptic
