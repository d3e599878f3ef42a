// SPDX-License-Identifier: AGPL-3.0-or-later
// Rays of the plenoptic camera: sensor points, lens lookup, ray generation, chief rays, the lenses
// whose light can reach a pixel (overlap).

#ifndef PLENOPTIC_RAYS_H
#define PLENOPTIC_RAYS_H

#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/core/sampling.h"

namespace plenoptic {

// A ray leaving the last optical element (the main-lens plane z = 0; the array when there is
// no main lens), in the optics frame, millimetres. The caller converts to scene units.
struct OpticsRay {
    Vec3 origin_mm;
    Vec3 dir;  // unit length, towards the scene (+z component)
    // What the ray's colour counts for in its pixel: 1, except for a real lens without an array,
    // whose samples cover a region of its exit pupil's plane (PupilBounds) rather than the paraxial
    // pupil: the region's area over the paraxial pupil's, so that a pixel's value does not depend
    // on the region sampled; and for an aimed sample behind an array (camera/aim.h): the sampled
    // part's share of the pixel times its share of the cell. With a lit-area table (PlenopticCamera::lit_area, a round stop): the area of
    // the region's lit part over the paraxial pupil's, and the pixel averages its passing
    // samples only (shade_pixel).
    double weight;
    // false: an aperture blocks the ray (it then carries no light), or the geometry has no such
    // ray; the other fields are then meaningless.
    bool passed;
};

// Centre of a lens in the optics frame (posed array), mm.
Vec3 lens_centre_mm(const PlenopticCamera& model, LensIndex lens);

// The lens a sensor point belongs to: the lens whose cell contains the intersection of the line
// (main-lens centre -> point) with the array plane; with no main lens, the lens straight above
// the point. Not found when that line misses the array plane (only for extreme tilts).
struct OwnLens {
    LensIndex lens;
    bool found;
};
OwnLens own_lens(const PlenopticCamera& model, Vec3 sensor_point_mm);

// The ray of one sample of pixel (i, j). `lens` forces the microlens the light passes through
// (overlap modelling); nullptr uses the own lens of the sample's sensor point. Not passed when
// an aperture blocks the ray (it then carries no light: black, opaque). No allocation, no
// search over lenses, no trigonometry except the concentric disc map of a bare main lens.
// When the camera aims its samples (model.sampling.aim, camera/aim.h), the sample's pixel point and
// cell point are drawn from the parts of the pixel and of the cell where light can pass, and the
// ray's weight carries those parts' shares: the pixel's value is unchanged in expectation.
OpticsRay generate_ray(const PlenopticCamera& model, int i, int j, const CameraSample& sample, const LensIndex* lens = nullptr);
// The same with the sample's pixel point and cell point as they are, never aimed (uniform over
// the pixel and the cell, weight 1 but for the radiometry): for those who ask whether light passes
// at a given sensor point and cell point (the microimage truth, the dark-image check).
OpticsRay generate_ray_unaimed(const PlenopticCamera& model, int i, int j, const CameraSample& sample,
                               const LensIndex* lens = nullptr);

// The lenses whose light can reach pixel (i, j) when the model models overlap: the pixel
// centre's own lens first, then every neighbour within model.overlap.rings rings that passes a
// conservative reach test (all of them for an array tilted by more than kMaxPrunedTiltSine).
// Without overlap modelling: the own lens only. Returns the count (0 if the pixel sees no lens),
// at most `capacity`.
int overlap_lenses(const PlenopticCamera& model, int i, int j, LensIndex* out, int capacity);

// The chief ray of pixel (i, j): pixel centre -> centre of its microlens (undeviated) -> refracted
// by the main lens; with no array, pixel centre through the main-lens centre; with a pinhole main
// lens, the pixel's only ray. Apertures are ignored (depth maps want a ray for every pixel).
// Falls back to the line from the pixel centre through the main-lens centre when the geometry
// has no such ray.
OpticsRay chief_ray(const PlenopticCamera& model, int i, int j);

// The same at continuous pixel coordinates (sensor_point's convention), optionally through a
// given lens. Not passed when the geometry has no such ray.
OpticsRay chief_ray_through(const PlenopticCamera& model, double pu, double pv, const LensIndex* lens = nullptr);

} // namespace plenoptic

#endif
