// SPDX-License-Identifier: AGPL-3.0-or-later
// The main lens's distortion profile (ground truth): over the field, the height at
// which the real chief ray meets the image plane against the paraxial image height.

#ifndef PLENOPTIC_DISTORTION_PROFILE_H
#define PLENOPTIC_DISTORTION_PROFILE_H

#include <vector>

#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

struct DistortionSample {
    double relative_field;      // paraxial height over the largest one, 0 .. 1
    double field_angle_deg;     // the chief ray's angle with the axis in object space
    double paraxial_height_mm;  // from the axis, on the image plane
    // Where the chief ray meets the image plane, along the direction of the paraxial image point
    // (positive on the same side). Distortion = real / paraxial - 1.
    double real_height_mm;
};

struct DistortionProfile {
    bool valid;                 // false: no main lens with an aperture, no real object plane, or fewer than 2 samples
    bool object_at_infinity;
    double object_plane_z_mm;   // optics frame; unused when the object is at infinity
    double image_plane_z_mm;    // -D: the array (the sensor without an array)
    std::vector<DistortionSample> samples;
};

// The profile of the plane that the lens images onto the plane z = -D (paraxially), at `count`
// paraxial heights evenly from 0 to the distance of the picture's farthest corner from the axis
// (on the sensor plane). The chief ray of an object point passes through the centre of the
// aperture stop: a thin lens's centre; a thick lens's entrance pupil centre (its paraxial model);
// for a traced prescription the ray found by the secant method whose crossing of the stop's plane
// is on the axis (clear apertures do not block it, as for the depth map's chief rays). A thin
// lens's parametric distortion is part of its trace. The samples stop at the first height whose
// chief ray does not exist (no ray through the stop's centre, or none reaching the image side).
// A lens that images z = -D from no real object (D inside the focal length) has no profile.
// With `through` (the same camera at another wavelength: at_wavelength), the object points are
// still this camera's (its paraxial heights and field), and their chief rays are found and traced
// through `through`'s lens: the heights at which that wavelength's chief rays meet the image plane,
// against the d line's paraxial heights (lateral colour is the difference between wavelengths).
DistortionProfile distortion_profile(const PlenopticCamera& model, int count, const PlenopticCamera* through = nullptr);

} // namespace plenoptic

#endif
