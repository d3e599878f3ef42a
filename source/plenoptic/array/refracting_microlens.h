// SPDX-License-Identifier: AGPL-3.0-or-later
// Refracting microlenses: plano-convex caps on a flat glass substrate, traced exactly (Snell's law
// at each surface, total internal reflection blocks the ray), either the curved side or the flat
// side facing the main lens.
//
// The lens's own frame (mm): its centre at the origin, its axis +z towards the scene, z = 0 the
// array's plane, which is the array's face nearest the sensor (the flat back when the caps face the
// scene, the caps' vertex plane when they face the sensor). The body extends towards the scene by
// L = t + T (cap centre thickness t, substrate T):
//   curved side towards the scene: flat face z = 0, cap vertex at z = L, surface z = L - sag(r);
//   curved side towards the sensor: cap vertex at z = 0, surface z = sag(r), flat face z = L;
// sag(r) = c r^2 / (1 + sqrt(1 - (1 + k) c^2 r^2)), c = 1 / R (R > 0: the cap bulges out of the
// glass). The cap's clear aperture is the lens's lattice cell: light passes a lens only where it
// meets both of its faces inside the lens's cell (the caller checks; the trace reports the points).
// The trace is a pure function of the shape, so a lens with its own pose (manufacturing errors)
// uses it unchanged in its own frame.

#ifndef PLENOPTIC_REFRACTING_MICROLENS_H
#define PLENOPTIC_REFRACTING_MICROLENS_H

#include <memory>

#include "plenoptic/array/microlens.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

struct RefractingShape {
    double radius_mm = 0;     // R > 0, the cap's radius of curvature at its vertex
    double conic = 0;         // k (0: a sphere)
    double ior = 1.5;         // n of the glass (cap and substrate)
    double cap_mm = 0;        // t: the cap's centre thickness
    double substrate_mm = 0;  // T: the substrate below the cap
    bool curved_towards_scene = true;

    double thickness_mm() const { return cap_mm + substrate_mm; }
    // The cap's sag at radius^2 r2 (NaN where the conic has no real root).
    double sag(double r2) const;
    // Paraxial data of the thick plano-convex lens in air: the effective focal length R / (n - 1)
    // (the thickness does not change it for a plane second surface), and the principal planes'
    // z in the lens frame: the one on the scene side (front) and on the sensor side (rear). The
    // principal plane of the curved side is its vertex; the flat side's lies L / n into the glass.
    double focal_length_mm() const { return radius_mm / (ior - 1); }
    double front_principal_z() const;
    double rear_principal_z() const;
};

// One path through the lens. Directions point towards the scene (+z) whichever way light goes.
struct RefractingPath {
    bool passed;          // false: the path misses a surface or is totally reflected inside
    Vec3 sensor_face;     // where it crosses the face nearest the sensor
    Vec3 scene_face;      // where it crosses the face nearest the scene
    Vec3 sensor_side_dir; // unit, in the air between the sensor and the lens
    Vec3 scene_side_dir;  // unit, in the air between the lens and the scene
};

// The ray on the sensor side whose line crosses the plane z = 0 at h0 with direction d (d.z > 0),
// through the lens towards the scene.
RefractingPath trace_to_scene(const RefractingShape& shape, Vec3 h0, Vec3 d);
// Light from the scene whose incoming line crosses the plane z = 0 at h with direction -d
// (d.z > 0: d points back towards the scene), through the lens towards the sensor.
RefractingPath trace_to_sensor(const RefractingShape& shape, Vec3 h, Vec3 d);

// Refracting microlenses of one shape.
std::shared_ptr<const Microlens> make_refracting_microlens(const RefractingShape& shape);
// The shape of refracting microlenses; nullptr for the other kinds.
const RefractingShape* refracting_shape(const Microlens& microlens);

// Whether the path of the array's sample_ray for these arguments passes the array after going on
// in a neighbour's column (it left its lens's cell inside the array); false for other lenses.
bool refracting_sample_crosses_cells(const MicrolensArray& array, const Vec3& p, LensIndex lens, double u, double v);

} // namespace plenoptic

#endif
