// SPDX-License-Identifier: AGPL-3.0-or-later
// Parametric distortion of the thin main lens: the Brown-Conrady radial (k1, k2,
// k3) and tangential (p1, p2) polynomial, as OpenCV, Zeller et al. and libpleno write it, applied
// where an image-side ray crosses the plane of the microlens array (the sensor without an array).
// Coordinates there are normalised by the main-lens-to-array distance D: (x, y) / D, the tangent
// of the image-side ray's angle from the lens centre. Pure maths, no POV-Ray dependency.

#ifndef PLENOPTIC_DISTORTION_H
#define PLENOPTIC_DISTORTION_H

#include <string>

#include "plenoptic/core/vec.h"

namespace plenoptic {

struct DistortionParams {
    double radial[3];      // k1, k2, k3
    double tangential[2];  // p1, p2
};

// Whether every coefficient is zero (the ideal lens).
bool is_identity(const DistortionParams& d);

// The distorted point of an ideal (undistorted) normalised point u, r^2 = u.x^2 + u.y^2:
//   x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y
Vec2 distort(const DistortionParams& d, Vec2 u);

// The ideal point whose distorted point is `distorted`, by Newton's method from the point itself.
// False when it does not converge to 1e-12 (beyond the region where the map is one to one).
bool undistort(const DistortionParams& d, Vec2 distorted, Vec2* ideal);

// Refusal (empty: fine): a coefficient that is not finite, or a map that folds over (its Jacobian
// not positive) somewhere within `max_normalised_radius` of the axis, where rays must be mapped.
std::string check_distortion(const DistortionParams& d, double max_normalised_radius);

} // namespace plenoptic

#endif
