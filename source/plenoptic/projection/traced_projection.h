// SPDX-License-Identifier: AGPL-3.0-or-later
// Forward projection through a traced main lens: where a 3-D point images, found by
// tracing its light through the lens ray by ray, since a real lens has no closed-form image.

#ifndef PLENOPTIC_TRACED_PROJECTION_H
#define PLENOPTIC_TRACED_PROJECTION_H

#include <vector>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/projection/projection.h"

namespace plenoptic {

// How finely the point's light is sampled.
struct TracedProjectionOptions {
    // Grid cells per lens pitch (each way) across the point's footprint on the array.
    int cells_per_pitch;
    // A cell whose corner rays do not all end alike (one lens, or blocked) is integrated from
    // subdivision x subdivision rays; the others from their corners.
    int subdivision;
    // Bounds on the grid (cells each way over the part of the front window light passes): at
    // least min_grid, at most max_grid (they bound the work per point).
    int min_grid, max_grid;
};

TracedProjectionOptions default_traced_projection_options();

// The images of a point (optics frame, mm) through the model's main lens, traced: rays from the
// point to a regular grid over the part of the lens's front window (the plane of its front
// vertex) through which light passes, each weighted by the solid angle it stands for, traced
// with every aperture (model.lens->to_image), then to the array, through their microlens
// (sensor_hit_through_lens) and to the sensor; grid cells that straddle an edge of the light are
// subdivided. Same meaning as forward_project:
// - thin microlenses: per lens, the weighted centroid of the delivered light (inside the picture
//   and the microimage cells the renderer gives that lens's light to); fraction = its weight over
//   the weight of all light through the main lens;
// - pinhole microlenses: per lens the point's light reaches, the one ray through its centre,
//   found by Newton's method from the nearest grid ray; fraction 1;
// - no array: the centroid of the point's spot on the sensor (its blur and aberrations), kept
//   when it lies in the picture; fraction 1.
// Points not in front of the front window by more than twice its sag image nowhere. Needs a main
// lens with an aperture (thin lens or prescription); deterministic (no threads, no randomness).
std::vector<PixelHit> forward_project_traced(const PlenopticCamera& model, Vec3 point,
                                             const TracedProjectionOptions& options);

} // namespace plenoptic

#endif
