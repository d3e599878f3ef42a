// SPDX-License-Identifier: AGPL-3.0-or-later
// The radial-tangential distortion polynomial and its inverse.

#include "plenoptic/lens/distortion.h"

#include <cmath>
#include <sstream>
#include <string>

namespace plenoptic {

namespace {

// Jacobian d(distorted)/d(ideal) at u: [[a, b], [c, e]].
void jacobian(const DistortionParams& d, Vec2 u, double* a, double* b, double* c, double* e)
{
    const double x = u.x, y = u.y, r2 = x * x + y * y;
    const double k1 = d.radial[0], k2 = d.radial[1], k3 = d.radial[2];
    const double p1 = d.tangential[0], p2 = d.tangential[1];
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial = k1 + r2 * (2 * k2 + 3 * k3 * r2);  // d(radial)/d(r2)
    *a = radial + x * dradial * 2 * x + 2 * p1 * y + p2 * 6 * x;
    *b = x * dradial * 2 * y + 2 * p1 * x + p2 * 2 * y;
    *c = y * dradial * 2 * x + p1 * 2 * x + 2 * p2 * y;
    *e = radial + y * dradial * 2 * y + p1 * 6 * y + 2 * p2 * x;
}

std::string number(double v)
{
    std::ostringstream out;
    out.precision(6);
    out << v;
    return out.str();
}

} // namespace

bool is_identity(const DistortionParams& d)
{
    return d.radial[0] == 0 && d.radial[1] == 0 && d.radial[2] == 0 && d.tangential[0] == 0 && d.tangential[1] == 0;
}

Vec2 distort(const DistortionParams& d, Vec2 u)
{
    const double x = u.x, y = u.y, r2 = x * x + y * y;
    const double radial = 1 + r2 * (d.radial[0] + r2 * (d.radial[1] + r2 * d.radial[2]));
    const double p1 = d.tangential[0], p2 = d.tangential[1];
    return Vec2{x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x), y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

bool undistort(const DistortionParams& d, Vec2 distorted, Vec2* ideal)
{
    Vec2 u = distorted;
    const double scale = 1 + std::fabs(distorted.x) + std::fabs(distorted.y);
    for (int iteration = 0; iteration < 50; ++iteration) {
        const Vec2 f = distort(d, u) - distorted;
        if (!is_finite(f))
            return false;
        if (std::fabs(f.x) + std::fabs(f.y) <= 1e-14 * scale) {
            *ideal = u;
            return true;
        }
        double a, b, c, e;
        jacobian(d, u, &a, &b, &c, &e);
        const double det = a * e - b * c;
        if (!(det > 0) || !std::isfinite(det))
            return false;
        u = Vec2{u.x - (e * f.x - b * f.y) / det, u.y - (-c * f.x + a * f.y) / det};
    }
    const Vec2 f = distort(d, u) - distorted;
    if (is_finite(f) && std::fabs(f.x) + std::fabs(f.y) <= 1e-12 * scale) {
        *ideal = u;
        return true;
    }
    return false;
}

std::string check_distortion(const DistortionParams& d, double max_normalised_radius)
{
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(d.radial[i]))
            return "main_lens distortion radial: k" + std::to_string(i + 1) + " must be a finite number";
    for (int i = 0; i < 2; ++i)
        if (!std::isfinite(d.tangential[i]))
            return "main_lens distortion tangential: p" + std::to_string(i + 1) + " must be a finite number";
    if (is_identity(d) || !(max_normalised_radius > 0) || !std::isfinite(max_normalised_radius))
        return "";
    // The map must stay one to one over the disc the rays cross: its Jacobian positive on a
    // polar grid (64 radii x 128 angles) out to that radius.
    for (int i = 1; i <= 64; ++i) {
        const double r = max_normalised_radius * i / 64;
        for (int j = 0; j < 128; ++j) {
            const double angle = 2 * kPi * j / 128;
            double a, b, c, e;
            jacobian(d, Vec2{r * std::cos(angle), r * std::sin(angle)}, &a, &b, &c, &e);
            if (!(a * e - b * c > 0))
                return "main_lens distortion folds the image over at " + number(r) +
                       " (normalised radius: distance from the axis on the array plane over D), inside the " +
                       number(max_normalised_radius) +
                       " the camera's rays reach: its map must be one to one there (smaller coefficients)";
        }
    }
    return "";
}

} // namespace plenoptic
