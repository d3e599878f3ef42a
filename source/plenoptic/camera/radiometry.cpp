// SPDX-License-Identifier: AGPL-3.0-or-later
// The irradiance normalisation (see the header).

#include "plenoptic/camera/radiometry.h"

#include <cmath>

#include "plenoptic/core/lattice.h"

namespace plenoptic {

namespace {

// Points a side of the midpoint grid over a microlens cell for its mean cos^4.
const int kCellGrid = 256;
// Rings of the midpoint rule over an exit pupil's disc.
const int kDiscRings = 4096;

// The mean of cos^m over a microlens cell, seen from the point at distance d under its centre.
double mean_cos_power_over_cell(const PlenopticCamera& m, double d, double power)
{
    double total = 0;
    for (int b = 0; b < kCellGrid; ++b)
        for (int a = 0; a < kCellGrid; ++a) {
            const Vec2 q = m.array.cell_point((a + 0.5) / kCellGrid, (b + 0.5) / kCellGrid);
            total += std::pow(d * d / (d * d + q.x * q.x + q.y * q.y), 0.5 * power);
        }
    return total / (kCellGrid * kCellGrid);
}

// The mean of cos^m over a disc of radius a seen from the point at distance h on its axis: the
// midpoint rule on kDiscRings rings of equal width (the integrand is smooth in the radius).
double mean_cos_power_over_disc(double a, double h, double power)
{
    if (!(a > 0))
        return 1;
    double total = 0;
    for (int k = 0; k < kDiscRings; ++k) {
        const double rho = (k + 0.5) / kDiscRings * a;
        total += std::pow(h * h / (h * h + rho * rho), 0.5 * power) * 2 * rho * (a / kDiscRings);
    }
    return total / (a * a);
}

} // namespace

double irradiance_constant_mm2(const PlenopticCamera& m)
{
    if (m.sensor.radiometry != Radiometry::Irradiance)
        return 0;
    const double power = 4 + m.sensor.angular_exponent;
    if (m.array.grid == GridType::None) {
        // The sampled domain is the exit pupil's disc (a pinhole's point: the limit a -> 0), C is
        // its on-axis A mean(cos^4) / h^2 = pi a^2 / (h^2 + a^2) without an angular response,
        // so K = h^2 / mean(cos^m). A traced lens's samples cover the pupil-bounds disc instead;
        // their flat weight (its area over the paraxial pupil's) carries that difference.
        const double h = m.lens->exit_pupil_centre().z - m.sensor.z_mm;
        const double a = m.lens->exit_pupil_radius();
        if (m.sensor.angular_exponent == 0)
            return h * h + a * a;  // the closed form of the mean of cos^4
        return h * h / mean_cos_power_over_disc(a, h, power);
    }
    // The pixel under the centre of a lens, at d, lit through the lens's whole cell: K = A / C
    // with C = A * mean(cos^m) / d^2 (a pinhole microlens's point: mean 1).
    const double d = effective_array_distance_mm(m);
    if (!m.array.microlens->forms_image())
        return d * d;
    return d * d / mean_cos_power_over_cell(m, d, power);
}

double reference_projected_solid_angle_sr(const PlenopticCamera& m)
{
    if (m.sensor.radiometry != Radiometry::Irradiance)
        return 0;
    if (m.array.grid == GridType::None)
        return !m.lens->forms_image() ? 0 : kPi * std::pow(m.lens->exit_pupil_radius(), 2) / m.sensor.irradiance_k_mm2;
    if (!m.array.microlens->forms_image())
        return 0;  // a pinhole microlens's point
    return m.array.pitch_mm * m.array.row_spacing_mm() / m.sensor.irradiance_k_mm2;  // A / K
}

const char* radiometry_name(Radiometry radiometry)
{
    return radiometry == Radiometry::Irradiance ? "irradiance" : "flat";
}

} // namespace plenoptic
