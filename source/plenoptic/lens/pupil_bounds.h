// SPDX-License-Identifier: AGPL-3.0-or-later
// Where light from a point behind a real main lens can pass it:
// per distance from the axis, a disc of the exit pupil's plane that holds every point of that
// plane through which a ray from the point passes all of the lens's apertures. Computed once per
// render from the exact trace; ray generation samples that disc instead of the whole rear element,
// so few samples are wasted, and the overlap bound of a plenoptic camera uses its reach.

#ifndef PLENOPTIC_PUPIL_BOUNDS_H
#define PLENOPTIC_PUPIL_BOUNDS_H

#include <vector>

#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

// A disc in the plane z = centre.z (optics frame, mm). Radius 0: no light passes.
struct PupilDisc {
    Vec3 centre;
    double radius;
};

class PupilBounds {
public:
    // Bounds for points of the plane z = plane_z (optics frame: the sensor, or the microlens
    // array) behind `traced`, the exact lens of `lens` (rear vertex at z = 0). The iris is ignored
    // (the round stop holds it), so `traced` should be built without blades.
    PupilBounds(const Prescription& lens, const MainLens& traced, double plane_z);
    // The same bounds and, with `tight`, also tight discs for samples aimed where light passes
    // (camera/aim.h; disc_holding with tight true): each bin's region measured along
    // kTightAzimuths directions from the middle of its x extent, bounded between two directions by
    // where the neighbouring chords' lines meet (a convex region's boundary cannot pass them,
    // corners included) instead of the 1 % margins; each span's disc holds the discs measured at
    // its bins and three field radii between them, widened by kTightMargin; and two cutting discs
    // per span (discs_holding). Conservative as the bounds are, by brute force
    // (pupil_bounds_test, the triplet and the catalogue's lenses); about 8 times the bounds'
    // traces to make.
    PupilBounds(const Prescription& lens, const MainLens& traced, double plane_z, bool tight);

    // The disc for a point of that plane (its z is not looked at): it holds every point of the
    // exit pupil's plane through which light from the point can pass.
    PupilDisc disc_for(Vec3 point) const;
    // A disc holding disc_for(q) for every point q of the bounds' plane within `radius` of
    // `centre` (its z is not looked at): where light from anywhere in a microlens's cell can pass.
    // Radius 0 when no light passes from any of them.
    // With `tight`, from the tight discs when the bounds were made with them (otherwise the same).
    PupilDisc disc_holding(Vec3 centre, double radius, bool tight = false) const;
    // Whether the bounds hold tight discs too.
    bool has_tight() const { return !tight_spans_.empty(); }
    // With tight discs: the tight disc_holding and, for a cell off the axis, two cutting discs that
    // also hold disc_for's region for every point of the cell (a cat's eye is their intersection
    // more closely than a disc); returns how many of out[0..2] it wrote (1 or 3).
    int discs_holding(Vec3 centre, double radius, PupilDisc out[3]) const;

    // False when the ray from `point` (of the bounds' plane) along `direction` certainly misses the
    // lens: it crosses the exit pupil's plane outside disc_for(point). True otherwise (the ray may
    // pass; only the exact trace says), and for a ray that does not head for the pupil's plane.
    bool may_pass(Vec3 point, Vec3 direction) const;

    // The farthest any passing ray crosses the exit pupil's plane from the axis point where the
    // line from a field point through the exit-pupil centre crosses it, over the whole field.
    double reach_mm() const { return reach_mm_; }
    // Beyond this distance from the axis, no light passes the lens.
    double field_radius_mm() const { return field_radius_mm_; }
    // The plane of the points the bounds are for (optics frame, mm).
    double plane_z() const { return plane_z_; }

private:
    // Per bin i (field radius i * step): the disc for a point on +x, its centre on the x axis.
    struct Bin {
        double centre_x;
        double radius;
    };
    double plane_z_;
    double pupil_z_;
    double step_mm_;
    double field_radius_mm_;
    double reach_mm_;
    std::vector<Bin> spans_;  // span i: a disc holding bins i and i + 1 (points between them)
    std::vector<Bin> tight_spans_;  // the same, tight (empty unless asked for)
    std::vector<Bin> cut_lo_spans_, cut_hi_spans_;  // the cutting discs (centred below and above)
    PupilDisc holding(const std::vector<Bin>& spans, double step_mm, Vec3 centre, double radius, bool exact_turn) const;
};

} // namespace plenoptic

#endif
