// SPDX-License-Identifier: AGPL-3.0-or-later
// Blur-aware ground truth: the radius of a point's defocus blur on the sensor, per image of it,
// as libpleno's blur-aware point (BAP) model defines it for focused plenoptic cameras.

#ifndef PLENOPTIC_BLUR_H
#define PLENOPTIC_BLUR_H

#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// The signed blur radius, in pixels (x pixel size), of a scene point (optics frame, mm) imaged
// through microlens `lens` (row form):
//   r = (A / 2) d (1/f - 1/a - 1/d)
// A: the microlens diameter, taken as the pitch (libpleno's); f: the lens's focal length (its
// type's); d: the lens centre's distance to the sensor plane; a: the signed distance from the
// array plane to what the microlens images, along the array's normal, positive towards the main
// lens: the main lens's paraxial image of the point, or the point itself without a main lens
// (1/a = 0 for an image at infinity). |r| is the radius of the disc of light a wholly lit
// microlens of diameter A spreads the point over; r > 0 when the microlens focuses the point in
// front of the sensor, r < 0 behind it, 0 in focus. A microlens that a point's cone of light
// covers only in part spreads it over less (the forward projection's fraction says how much).
// Without an array: the main lens's own blur, exit-pupil radius x (s / b - 1) (s, b: sensor and
// image distances from the exit pupil), with the same sign rule. 0 where each image is a single
// ray (pinhole microlenses, a pinhole main lens); NaN where the point forms no image.
double blur_radius_px(const PlenopticCamera& model, Vec3 point_mm, LensIndex lens);

} // namespace plenoptic

#endif
