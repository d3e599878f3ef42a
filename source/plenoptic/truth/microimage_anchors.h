// SPDX-License-Identifier: AGPL-3.0-or-later
// The microimage truth between anchors (truth/microimages.h): refracting lenses measured every
// anchor_step lenses and interpolated by a cubic between them where the anchors vouch for it, and
// the canonical pose the anchors of a turned or moved array are measured in. Shared by the truth's
// sources in truth/; not for other users.

#ifndef PLENOPTIC_MICROIMAGE_ANCHORS_H
#define PLENOPTIC_MICROIMAGE_ANCHORS_H

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/truth/microimage_measure.h"

namespace plenoptic {
namespace microimage_detail {

// Refracting microlenses on an ideal array: every lens of the array sees its own part of the main
// lens's light through the same glass, so its microimage's offset from its lattice centre and its
// lit fraction are smooth functions of where the lens is. Those lenses are measured exactly at
// anchors, every anchor_step-th lens of every anchor_step-th row, and interpolated between them
// (a cubic in each direction, on the 4 x 4 anchors nearest the lens), wherever the anchors say the
// cubic holds; the other lenses are measured. A lens's position in lattice units: X = k (+ 1/2 on
// the odd rows of a hexagonal array), Y = l. (The anchors' grid is symmetric under the mirrors of
// Symmetry: an anchor's quarter lens is an anchor.)
double lattice_x(GridType grid, LensIndex lens);

// The cubic through four anchors at 0, 1, 2, 3, at t: its weights.
void cubic_weights(double t, double w[4]);

// The cubic's error, from fourth differences of the anchors: the cubic through four points at unit
// steps misses a function by f''''(xi) / 24 |t (t - 1) (t - 2) (t - 3)| at t (at most 0.023 f''''
// between the middle two, 0.042 between the outer ones at the array's edge), and f'''' is about the
// fourth difference of five anchors, the larger of the two windows that hold the four; the error of
// the two directions' cubics add. With a margin of 1.5 on that estimate.
double cubic_error(double t, double fourth_difference);

// One anchor: its lens's offset from its lattice centre (pixels) and its lit fraction.
struct AnchorValue {
    bool lit;
    double value[3];  // du, dv, lit fraction
    // A region of its microimage is a lobe of light that crossed into a neighbour's column
    // (region_moments).
    bool lobe;
};

// The anchors of one level: lenses (K step, L step), K = k0 .. k1, L = l0 .. l1, those measured
// in `values`.
struct Anchors {
    std::int64_t step = 0, k0 = 0, k1 = 0, l0 = 0, l1 = 0;
    const std::unordered_map<std::uint64_t, AnchorValue>* values = nullptr;

    // The first anchor (i0, j0) of the 4 x 4 of a lens at `at` (lattice units: X, Y above), and where
    // it lies in anchor units.
    void stencil(Vec2 at, std::int64_t* i0, std::int64_t* j0, double* x, double* y) const
    {
        *x = at.x / double(step);
        *y = at.y / double(step);
        *i0 = std::max(k0, std::min(k1 - 3, std::int64_t(std::floor(*x)) - 1));
        *j0 = std::max(l0, std::min(l1 - 3, std::int64_t(std::floor(*y)) - 1));
    }
    // Calls f(K, L) for each anchor the lens's interpolation reads: its 4 x 4 and the anchors one
    // beyond them along its rows and columns (for the fourth differences), inside the range.
    template <class F> void each(std::int64_t i0, std::int64_t j0, F f) const
    {
        for (std::int64_t j = std::max(l0, j0 - 1); j <= std::min(l1, j0 + 4); ++j)
            for (std::int64_t i = std::max(k0, i0 - 1); i <= std::min(k1, i0 + 4); ++i)
                if ((j >= j0 && j <= j0 + 3) || (i >= i0 && i <= i0 + 3))
                    f(i, j);
    }
    LensIndex lens(std::int64_t K, std::int64_t L) const { return LensIndex{K * step, L * step}; }

    // Anchors `s` lenses apart over lenses whose positions run from range[0] to range[1] (X) and
    // range[2] to range[3] (Y): one more below and two more above, so that every stencil fits.
    void cover(std::int64_t s, const double range[4]);
    // At least five anchors a side (the fourth differences need them).
    bool enough() const { return k1 - k0 >= 4 && l1 - l0 >= 4; }
    // The anchors that the lenses `lenses` (indices into `at`, their positions) read, once each and
    // in the order first read, those for which known(key) is false, as truths with the lens set.
    template <class Known>
    std::vector<MicroimageTruth> read_by(const std::vector<std::size_t>& lenses, const std::vector<Vec2>& at,
                                         const Known& known) const
    {
        std::vector<MicroimageTruth> read;
        std::unordered_map<std::uint64_t, char> seen;
        for (std::size_t index : lenses) {
            std::int64_t i0, j0;
            double x, y;
            stencil(at[index], &i0, &j0, &x, &y);
            each(i0, j0, [&](std::int64_t i, std::int64_t j) {
                const LensIndex anchor = lens(i, j);
                const std::uint64_t key = anchor_key(anchor);
                if (!known(key) && seen.emplace(key, 1).second) {
                    MicroimageTruth t = MicroimageTruth();
                    t.lens = anchor;
                    read.push_back(t);
                }
            });
        }
        return read;
    }
};

// The cubic through the 4 x 4 anchors from (i0, j0) (Anchors::stencil) of the value v(i, j, q), at
// (x, y) in anchor units, and in `error` the estimate of how far it misses the function: each
// direction's cubic_error from the largest fourth difference along it over the stencil's rows and
// columns, of each window of five anchors that holds the stencil's four (every anchor of
// Anchors::each is read).
template <class V>
double cubic_through(const Anchors& a, std::int64_t i0, std::int64_t j0, double x, double y, const V& v, int q,
                     double* error)
{
    double largest[2] = {0, 0};
    for (int across = 0; across < 4; ++across)
        for (std::int64_t first = -1; first <= 0; ++first) {
            if (i0 + first >= a.k0 && i0 + first + 4 <= a.k1) {
                const std::int64_t i = i0 + first, j = j0 + across;
                const double d4 =
                    v(i, j, q) - 4 * v(i + 1, j, q) + 6 * v(i + 2, j, q) - 4 * v(i + 3, j, q) + v(i + 4, j, q);
                largest[0] = std::max(largest[0], std::fabs(d4));
            }
            if (j0 + first >= a.l0 && j0 + first + 4 <= a.l1) {
                const std::int64_t i = i0 + across, j = j0 + first;
                const double d4 =
                    v(i, j, q) - 4 * v(i, j + 1, q) + 6 * v(i, j + 2, q) - 4 * v(i, j + 3, q) + v(i, j + 4, q);
                largest[1] = std::max(largest[1], std::fabs(d4));
            }
        }
    *error = cubic_error(x - double(i0), largest[0]) + cubic_error(y - double(j0), largest[1]);
    double wx[4], wy[4];
    cubic_weights(x - double(i0), wx);
    cubic_weights(y - double(j0), wy);
    double sum = 0;
    for (int j = 0; j < 4; ++j) {
        double row = 0;
        for (int i = 0; i < 4; ++i)
            row += wx[i] * v(i0 + i, j0 + j, q);
        sum += wy[j] * row;
    }
    return sum;
}

// The lens's microimage from the anchors, or false where the anchors do not vouch for the cubic (a
// dark anchor among those it reads, an anchor with a lobe of light that crossed cells, or a fourth
// difference too large). Lobes (refracting lenses without baffles, light that left its cell in
// the glass and then a neighbour's cap): thin regions apart from the lens's own light, counted
// only at the cell points whose own light is gone (each moved the centre by about 1e-3 px in the
// unit test); where a row of the 24 x 24 cell points begins to count them the centre steps by
// several thousandths of a pixel from one lens to the next (a step between anchors, which neither
// the cubic nor its fourth differences see), so lenses whose anchors count any are measured.
bool interpolate(const Anchors& a, Vec2 at, MicroimageTruth* truth, Vec2 lattice_px);

// Whether the truth interpolates between anchors: refracting microlenses (measured at 24 x 24
// cell points, 64 times a thin lens's cost) on an array without manufacturing errors.
bool interpolates(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options);

// Where the anchors are measured, and where a lens lies among them. Usually the camera itself, a
// lens at its lattice point. An ideal refracting array turned about the optical axis by other
// than a multiple of 90 degrees, or whose lens (0, 0) is off the axis, has no mirror symmetry; but
// the main lens and the sensor's plane are symmetric under every turn about the axis (every model
// is), so a lens's microimage is, turned, that of the same lens of the array turned back and moved
// onto the axis (its canonical pose), where Symmetry holds. The anchors are then measured in that
// array, and each lens interpolated at the point it occupies there (between lattice points: the
// cubic is a smooth function of position, as the microimage is of where the lens is), then turned
// back with the array. The rule's cell points turn with the array, its directions do not (they are
// laid out in pixels), so the answers are those of the same rule in a turned frame: the same
// accuracy, not the same bits (BENCHMARKS "The microimage truth by symmetry").
class Canonical {
public:
    Canonical(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options);
    bool active() const { return active_; }
    // The cameras the anchors are measured in.
    const PlenopticCamera& model() const { return active_ ? model_ : m_; }
    const PlenopticCamera& light() const { return active_ ? light_model_ : light_; }
    // Where the lens lies among those anchors, in lattice units (X, Y above); `shift` (array-local,
    // mm) moves it off its lattice point (a displaced lens: the ideal lens that sits where it sits).
    Vec2 position(LensIndex lens, Vec2 shift = Vec2{0, 0}) const;
    // The lens's lattice centre (moved by `shift`) projected onto the sensor from the exit pupil's
    // centre (pixels, centre convention) in the anchors' camera: what the interpolated offset is
    // added to.
    bool centre_px(LensIndex lens, Vec2* px, Vec2 shift = Vec2{0, 0}) const;
    // A sensor point of the anchors' camera (pixels, centre convention) in this camera: turned
    // about the axis with the array.
    Vec2 to_camera_px(Vec2 px) const;

private:
    // The lens's lattice point in the canonical array's frame: its place in the optics frame turned
    // back about the axis.
    Vec2 canonical_local(LensIndex lens, Vec2 shift) const;

    const PlenopticCamera& m_;
    const PlenopticCamera& light_;
    PlenopticCamera model_, light_model_;
    bool active_ = false;
    double turn_[2] = {1, 0};  // cos, sin of the array's turn about the axis
};

} // namespace microimage_detail
} // namespace plenoptic

#endif
