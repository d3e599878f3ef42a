// SPDX-License-Identifier: AGPL-3.0-or-later
// Virtual depth, the depth coordinate of focused (2.0) plenoptic cameras: where the main lens
// images a scene point, measured from the microlens array in units of d (array -> sensor).

#ifndef PLENOPTIC_VIRTUAL_DEPTH_H
#define PLENOPTIC_VIRTUAL_DEPTH_H

#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// Whether the camera is a focused (2.0) one: a main lens that forms an image (not a pinhole), an
// array of thin microlenses, and d different from the focal length of some lens type.
bool is_focused_camera(const PlenopticCamera& model);

// v = -a / d for a scene point (optics frame, mm): a is the signed distance from the array plane
// to the point's paraxial image through the main lens, along the array's normal, positive towards
// the main lens; d is the array -> sensor distance at the array centre. As in libpleno (and
// Raytrix's positive virtual depths): v > 0 for an image behind the array (Galilean), v < 0 for
// one in front of it (Keplerian), 0 on the array.
// NaN without an image: no main lens or a pinhole, a point on the front focal plane.
double virtual_depth(const PlenopticCamera& model, Vec3 point_mm);

// The virtual depth of what pixel (i, j)'s chief ray meets at the depth map's distance
// (scene units along the chief ray, truth/depth_map.h): +inf gives the virtual depth of the
// point at infinity in the ray's direction; a negative distance (a blocked pixel) gives NaN.
float pixel_virtual_depth(const PlenopticCamera& model, int i, int j, float distance_units);

} // namespace plenoptic

#endif
