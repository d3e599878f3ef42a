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
    // (camera/aim.h; disc_holding with tight true), on spans a quarter of the bins': each span end's
    // region measured along kTightAzimuths directions from the middle of its x extent, bounded
    // between two directions by where the neighbouring chords' lines meet (a convex region's
    // boundary cannot pass them, corners included) instead of the 1 % margins; each span's disc
    // holds those polygons, its extent linear across the span with an allowance for its curvature,
    // widened by kTightMargin; and two or four cutting discs per span (discs_holding). Conservative
    // as the bounds are, by brute force (pupil_bounds_test, the triplet and the catalogue's
    // lenses); about 8 times the bounds' traces to make.
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
    bool has_tight() const { return !tight_ramps_.empty(); }
    // With tight discs: the tight disc_holding and, for a cell off the axis, two cutting discs
    // centred on the line from the axis through the cell and, where they pay, two more centred off
    // it (mirror images), each also holding disc_for's region for every point of the cell (a cat's
    // eye is their intersection more closely than a disc); returns how many of out[0..4] it wrote
    // (1, 3 or 5).
    static const int kMaxDiscs = 5;
    int discs_holding(Vec3 centre, double radius, PupilDisc out[kMaxDiscs]) const;

    // False when the ray from `point` along `direction` certainly misses the lens: from where its
    // line crosses the bounds' plane, q, it crosses the exit pupil's plane outside disc_for(q). The
    // point may lie off that plane (a microlens displaced along the axis or tilted, a tilted array):
    // in the air behind the lens, where nothing else bends the ray, the line decides alone. True
    // otherwise (the ray may pass; only the exact trace says), and for a ray that does not head for
    // the pupil's plane or runs along the bounds' plane.
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
    double tight_step_mm_ = 0;  // the tight spans' (a fraction of step_mm_)
    double field_radius_mm_;
    double reach_mm_;
    std::vector<Bin> spans_;  // span i: a disc holding bins i and i + 1 (points between them)
    // A tight span's disc (centred on the x axis) as its x extent [lo, hi], linear from the span's
    // start (index 0) to its end (1); lit false: no light passes anywhere in the span.
    struct Ramp {
        bool lit = false;
        double lo[2] = {0, 0}, hi[2] = {0, 0};
        double y = 0;  // the centre's distance from the x axis (the off-axis pair: its upper disc)
        bool pair = false;  // an off-axis pair of the span's own (not its disc standing in)
    };
    std::vector<Ramp> tight_ramps_;  // tight spans of tight_step_mm_ (empty unless asked for)
    std::vector<Ramp> cut_lo_ramps_, cut_hi_ramps_;  // the cutting discs (centred below and above)
    // The pair of cutting discs off the axis, per span (a span without one: its disc); pairs_: some
    // span has one.
    std::vector<Ramp> pair_ramps_;
    bool pairs_ = false;
    PupilDisc holding(const std::vector<Bin>& spans, double step_mm, Vec3 centre, double radius) const;
    // pair (if given): set when a span met has a pair of its own.
    PupilDisc holding(const std::vector<Ramp>& ramps, Vec3 centre, double radius, bool mirror,
                      bool* pair = nullptr) const;
};

} // namespace plenoptic

#endif
