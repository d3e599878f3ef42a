// SPDX-License-Identifier: AGPL-3.0-or-later
// Helpers shared by the optics sources (rays, projection, microimage lattice); not for other users.

#ifndef PLENOPTIC_RAYS_INTERNAL_H
#define PLENOPTIC_RAYS_INTERNAL_H

#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {
namespace detail {

// Intersection of the line (main-lens centre -> p), or the vertical line through p when there is
// no main lens, with the array plane; array-local coordinates. False when they do not meet.
bool project_to_array(const PlenopticCamera& m, Vec3 p, Vec2* local);

} // namespace detail
} // namespace plenoptic

#endif
