// SPDX-License-Identifier: AGPL-3.0-or-later
// The radiometric kernel shared by the camera's radiometry (camera/radiometry.h, which explains
// K and the cos^4 law) and the lens's lit-area table (lens/lit_area.h).

#ifndef PLENOPTIC_IRRADIANCE_H
#define PLENOPTIC_IRRADIANCE_H

#include <cmath>

#include "plenoptic/core/vec.h"

namespace plenoptic {

// The weight of a sample whose ray leaves sensor point s towards point q of an aperture plane
// with unit normal n (towards the scene): K cos(t_s) cos(t_q) / |q - s|^2, times cos^e(t_s) for
// the pixel's angular response (sensor angular_response e; 0: none).
inline double irradiance_weight(double k_mm2, double exponent, Vec3 s, Vec3 q, Vec3 n)
{
    const Vec3 v = q - s;
    const double r2 = dot(v, v);
    const double weight = k_mm2 * v.z * dot(v, n) / (r2 * r2);
    return exponent > 0 ? weight * std::pow(v.z * v.z / r2, 0.5 * exponent) : weight;
}

} // namespace plenoptic

#endif
