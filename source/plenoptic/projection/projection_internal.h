// SPDX-License-Identifier: AGPL-3.0-or-later
// What the two forward projections share (projection/projection.cpp, closed form through ideal
// lenses; projection/traced_projection.cpp, numerical through a traced lens): how light through a
// microlens reaches the sensor, and which of it the renderer delivers.

#ifndef PLENOPTIC_PROJECTION_INTERNAL_H
#define PLENOPTIC_PROJECTION_INTERNAL_H

#include <vector>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/projection/projection.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {
namespace detail {

// Sensor hit of a ray arriving at array point h (optics frame) with direction `towards_sensor`,
// passed by `lens` as its kind passes light (Microlens::towards_sensor: a thin lens refracts it by
// the rule of ray generation, a pinhole lets it through unchanged, a refracting lens traces it
// through its glass and the ray goes on from where it leaves the lens). False when it does not
// reach the sensor plane.
bool sensor_hit_through_lens(const PlenopticCamera& m, LensIndex lens, Vec3 h, Vec3 towards_sensor, Vec3* hit);

// Lenses whose microimage cells may receive light through a lens: the renderer gives a sensor
// point light through lens L only if L is its own lens (no overlap modelling: the own lens of
// each sample's sensor point), or, with overlap modelling, if L lies within model.overlap.rings
// rings of the own lens of the pixel's centre (overlap_lenses; its reach test is conservative,
// so it never refuses light that arrives). Rings in skew indices: max(|dk|, |dl|) rectangular,
// max(|dk|, |dl|, |dk + dl|) hexagonal.
int receiving_rings(const PlenopticCamera& m);
bool within_rings(const PlenopticCamera& m, LensIndex a, LensIndex b, int rings);

// The picture on the sensor plane (x, y, mm).
std::vector<Vec2> picture_polygon(const PlenopticCamera& m);

// Lens `lens`'s microimage cell on the sensor plane: its cell seen from the main-lens centre
// (straight down without a main lens). Empty if a corner does not project.
std::vector<Vec2> microimage_cell(const PlenopticCamera& m, LensIndex lens);

// Whether the renderer delivers light through `lens` to sensor point s (x, y, mm): inside the
// picture and in the microimage cell of a lens within the receiving rings of `lens`.
bool delivered_point(const PlenopticCamera& m, LensIndex lens, Vec2 s);

// Adds the image at sensor point s if the renderer delivers light there through `lens`.
void add_point_hit(const PlenopticCamera& m, LensIndex lens, Vec3 s, double fraction, std::vector<PixelHit>* hits);

} // namespace detail
} // namespace plenoptic

#endif
