// SPDX-License-Identifier: AGPL-3.0-or-later
// Forward projection: where a 3-D point images on the sensor, one position per microlens.

#ifndef PLENOPTIC_PROJECTION_H
#define PLENOPTIC_PROJECTION_H

#include <vector>

#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// One image of a 3-D point: lens (k, l) in row form ((0, 0) when there is no array) and the
// continuous pixel position, centre convention (pixel (i, j)'s centre at (i, j)).
// fraction: the part of the point's light through the main aperture that arrives in this image
// (thin main lens with thin microlenses; 1 where every image is a single ray: pinholes, no array).
struct PixelHit {
    LensIndex lens;
    double u, v;
    double fraction;
};

// Every pixel position where a point (optics frame, mm) images: one per microlens through which
// the renderer delivers some of its light to the picture (docs/camera.md, "Forward projection").
// Thin main lens: the point's thin-lens image X' (homogeneous, so X' at infinity is fine), in
// front of, on or behind the array. A thin microlens passes the part of the cone (main aperture ->
// X') that falls in its cell and spreads it over a spot on the sensor; the image is the centroid of
// the part of that spot the renderer delivers: inside the picture and inside that lens's own
// microimage cell or, where the model models overlap, the microimage cells of the lenses within
// overlap_rings rings of it (the pixels whose overlap_lenses can hold it). A spot that has shrunk
// to a point (a focused 2.0 camera at its focused depth) is kept where it lands if delivered.
// Pinhole microlenses: each lens whose centre the cone covers images the point along the line
// from X' through that centre. Pinhole main lens: the single ray through the pinhole. No main
// lens: each lens images the point along the line through its centre (a camera array). No array:
// the chief ray through the main-lens centre. Points at or behind the main-lens plane image nowhere.
// A thick lens is the thin lens between its principal planes, its exit pupil the aperture. A traced
// (prescription) lens and a distorted thin lens have no closed form: forward_project_traced
// (projection/traced_projection.h).
std::vector<PixelHit> forward_project(const PlenopticCamera& model, Vec3 point_mm);

} // namespace plenoptic

#endif
