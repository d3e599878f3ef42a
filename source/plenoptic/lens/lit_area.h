// SPDX-License-Identifier: AGPL-3.0-or-later
// How much light reaches a sensor point behind a real main lens without a microlens array:
// per distance from the axis, the area of the exit pupil's plane through which rays
// from the point pass every aperture of the lens, relative to the paraxial exit pupil's area.
//
// A pixel's samples cover the pupil-bounds disc (lens/pupil_bounds.h); some of them are
// blocked (the disc holds the lit region loosely, and off axis the clear apertures cut it into
// a cat's eye). Measuring that loss per pixel takes many more traces than the pixel's own
// samples; behind a lens with a round stop it is a function of the distance from the axis
// alone, so it is measured once per render here, on fine radii, and a pixel's value is the mean
// colour of its passing samples times this relative area (camera/pixel.h).

#ifndef PLENOPTIC_LIT_AREA_H
#define PLENOPTIC_LIT_AREA_H

#include <vector>

#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/pupil_bounds.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

class LitAreaTable {
public:
    // For points of the sensor plane behind `traced`, an exact lens with a round stop (no iris
    // blades: the lit region of a point on the +x axis is then symmetric about that axis and
    // turns with the point's azimuth), whose light falls within `bounds`' discs. With
    // irradiance_k_mm2 > 0 (irradiance radiometry, camera/radiometry.h) every lit point of the
    // pupil's plane counts with its irradiance weight, so the table holds E / (L C).
    LitAreaTable(const MainLens& traced, const PupilBounds& bounds, double irradiance_k_mm2, double angular_exponent = 0);

    // The lit area of the exit pupil's plane for a sensor point (its z is not looked at), over
    // the paraxial exit pupil's area: 1 on the axis of an aberration-free lens, falling with
    // mechanical vignetting; 0 beyond the field. Under irradiance radiometry, the lit area
    // weighted by the cos^4 law, with the same normalisation.
    double at(Vec3 point) const;

    // Radii tabulated, from the axis to the edge of the field (for tests and reports).
    int size() const { return int(relative_area_.size()); }
    double step_mm() const { return step_mm_; }
    double value(int index) const { return relative_area_[size_t(index)]; }

private:
    double step_mm_;
    std::vector<double> relative_area_;  // at radii index * step_mm_
};

} // namespace plenoptic

#endif
