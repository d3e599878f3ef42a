// SPDX-License-Identifier: AGPL-3.0-or-later
// Helpers shared by the optics sources (rays, projection, microimage lattice); not for other users.

#ifndef PLENOPTIC_RAYS_INTERNAL_H
#define PLENOPTIC_RAYS_INTERNAL_H

#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/model.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {
namespace detail {

inline Vec3 to_local(const Model& m, Vec3 q) { return mul_transposed(m.pose.rotation, q - m.pose.centre_mm); }
inline Vec3 to_optics(const Model& m, Vec3 local) { return m.pose.centre_mm + mul(m.pose.rotation, local); }

inline double microlens_focal(const Model& m, LensIndex lens)
{
    return m.microlens_focal_mm[lens_type(lens, m.lens_type_count)];
}

// Intersection of the line (main-lens centre -> p), or the vertical line through p when there is
// no main lens, with the array plane; array-local coordinates. False when they do not meet.
bool project_to_array(const Model& m, Vec3 p, Vec2* local);

} // namespace detail
} // namespace plenoptic

#endif
