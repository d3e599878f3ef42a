// SPDX-License-Identifier: AGPL-3.0-or-later
// Does light reach the sensor at all? A parse-time estimate from the camera's own sample points
// (geometry only, no scene), so that parameters that leave the image black are not silent.

#ifndef PLENOPTIC_LIGHT_CHECK_H
#define PLENOPTIC_LIGHT_CHECK_H

#include <string>

#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// Below this fraction of passing sample points near the axis, the image is (nearly) black.
const double kDarkImageFraction = 1e-3;

// The fraction of the sample points of the pixels around the optical axis (a patch of about
// three microimages across, at most 64 x 64 pixels, 16 points each) that pass every aperture.
double lit_fraction_near_axis(const PlenopticCamera& model);

// A warning when lit_fraction_near_axis is below kDarkImageFraction: what passes, and the
// usual causes (a tiny main-lens aperture; a focus distance at the focal length, which puts
// the array far behind the lens). Empty otherwise.
std::string dark_image_warning(const PlenopticCamera& model);

} // namespace plenoptic

#endif
