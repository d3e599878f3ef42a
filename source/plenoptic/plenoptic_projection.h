// SPDX-License-Identifier: AGPL-3.0-or-later
// Forward projection: where a 3-D point images on the sensor, one position per microlens.

#ifndef PLENOPTIC_PROJECTION_H
#define PLENOPTIC_PROJECTION_H

#include <vector>

#include "plenoptic_lattice.h"
#include "plenoptic_model.h"

namespace plenoptic {

// One image of a 3-D point: lens (k, l) in row form ((0, 0) when there is no array) and the
// continuous pixel position, centre convention (pixel (i, j)'s centre at (i, j)).
struct PixelHit {
    LensIndex lens;
    double u, v;
};

// Every pixel position where a point (optics frame, mm) images, one per microlens that sees it.
// Thin main lens: the point's thin-lens image X' (homogeneous, so X' at infinity is fine); each
// lens whose cell meets the cone from the main aperture to X' images it along the line from X'
// through its centre (its chief ray). Kept only inside that lens's microimage cell and inside the
// image. Pinhole main lens: the single ray through the pinhole. No main lens: each lens images
// the point along the line through its centre (a camera array). No array: the chief ray through
// the main-lens centre. Points at or behind the main-lens plane image nowhere.
std::vector<PixelHit> forward_project(const Model& model, int W, int H, const double point_mm[3]);

} // namespace plenoptic

#endif
