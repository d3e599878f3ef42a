// SPDX-License-Identifier: AGPL-3.0-or-later
// The lit-area table of a real lens without an array (see the header).
//
// At each tabulated radius r the point P = (r, 0, sensor) is traced towards kPoints points of
// the upper half of its pupil-bounds disc: a Fibonacci lattice mapped to the half disc by an
// area-preserving polar map. The lens is symmetric about the plane y = 0 through P (centred
// rotationally symmetric surfaces: spheres, conics, even aspheres; a round stop), so the lower
// half passes where the upper half does, and the half disc at kPoints points is the whole disc at twice as many. Lit area = disc area times
// the passing share (each passing point counting with its irradiance weight under irradiance
// radiometry).

#include "plenoptic/lens/lit_area.h"

#include <cmath>
#include <cstdint>

#include "plenoptic/core/irradiance.h"
#include "plenoptic/core/setup_progress.h"

namespace plenoptic {

namespace {

const int kIntervals = 256;     // tabulated radii from the axis to the edge of the field, minus one
const int kPoints = 987;        // lattice points on the half disc (a Fibonacci number, F16)
const int kLatticeStep = 610;   // F15: the Fibonacci lattice's generator
double relative_lit_area(const MainLens& traced, const PupilBounds& bounds, double r, double paraxial_area,
                         double irradiance_k_mm2, double angular_exponent)
{
    const Vec3 from{r, 0, bounds.plane_z()};
    const PupilDisc disc = bounds.disc_for(from);
    if (!(disc.radius > 0))
        return 0;
    double passing = 0;
    for (int k = 0; k < kPoints; ++k) {
        const double u = (k + 0.5) / kPoints;
        const double v = double((std::int64_t(k) * kLatticeStep) % kPoints) / kPoints + 0.5 / kPoints;
        const double rho = disc.radius * std::sqrt(u);
        const double angle = kPi * v;
        const Vec3 target{disc.centre.x + rho * std::cos(angle), disc.centre.y + rho * std::sin(angle), disc.centre.z};
        if (traced.to_scene(from, target - from, true).passed)
            passing += irradiance_k_mm2 > 0 ? irradiance_weight(irradiance_k_mm2, angular_exponent, from, target, Vec3{0, 0, 1}) : 1.0;
    }
    const double disc_area = kPi * disc.radius * disc.radius;
    return disc_area * passing / kPoints / paraxial_area;
}

} // namespace

LitAreaTable::LitAreaTable(const MainLens& traced, const PupilBounds& bounds, double irradiance_k_mm2,
                           double angular_exponent)
    : step_mm_(bounds.field_radius_mm() / kIntervals)
{
    const double pupil = traced.exit_pupil_radius();
    const double paraxial_area = kPi * pupil * pupil;
    if (!(step_mm_ > 0) || !(paraxial_area > 0))
        return;  // no light passes anywhere: an empty table, at() is 0
    for (int i = 0; i <= kIntervals; ++i) {
        report_setup("lit-area table", i, kIntervals + 1);
        relative_area_.push_back(relative_lit_area(traced, bounds, i * step_mm_, paraxial_area, irradiance_k_mm2, angular_exponent));
    }
    report_setup("lit-area table", kIntervals + 1, kIntervals + 1);
}

double LitAreaTable::at(Vec3 point) const
{
    if (relative_area_.empty())
        return 0;
    // Not hypot: radii of millimetres neither overflow nor underflow, and this runs per sample.
    const double at = std::sqrt(point.x * point.x + point.y * point.y) / step_mm_;
    if (!(at < kIntervals))
        return 0;
    const size_t i = size_t(at);
    const double t = at - double(i);
    return (1 - t) * relative_area_[i] + t * relative_area_[i + 1];
}

} // namespace plenoptic
