// SPDX-License-Identifier: AGPL-3.0-or-later
// The microimage truth of refracting lenses with manufacturing errors, corrected from Jacobian
// anchors (truth/microimages.h, MicroimageOptions::error_anchor_step). Shared by the truth's
// sources in truth/; not for other users.

#ifndef PLENOPTIC_MICROIMAGE_ERRORS_H
#define PLENOPTIC_MICROIMAGE_ERRORS_H

#include <cstddef>
#include <vector>

#include "plenoptic/truth/microimage_anchors.h"

namespace plenoptic {
namespace microimage_detail {

// Manufacturing errors on refracting microlenses, corrected (MicroimageOptions::error_anchor_step;
// renders with the camera's microimage_error_anchors N; by default every lens is measured).
// Measuring each lens costs some 150 ms (its 24 x 24 cell points, its regions less alike its
// neighbour's than on an ideal array), ten hours for a raw; but the errors are small (a fraction of a
// micrometre, a few per cent, a fraction of a degree) and a lens's microimage changes smoothly with
// most of them. So a lens with errors is taken as the ideal lens that sits where it sits (the
// anchors' cubic at its displaced centre: its cell and its neighbours moved with it), corrected to
// second order in each of its parameters x_p:
// its displacement along the axis, its focal factor less 1, its axis's x and y, and each adjacent
// lens's displacement from it (x and y, array frame: where the walls between their columns and the
// bisector that cuts its cell lie). The correction is the sum over p of J_p x_p + H_p x_p^2 / 2 +
// K_p x_p x_f (x_f the focal factor's), J_p, H_p and K_p the central, second and mixed differences
// of Jacobian anchors error_anchor_step lenses apart, each measured with x_p = +h_p and -h_p alone
// (h_p the largest |x_p| the errors give; a lens's own for a displacement), and with x_p = h_p and
// x_f = +-h_f; the corrections the 4 x 4 Jacobian anchors nearest the lens give for its x are
// interpolated by the cubic where their fourth differences vouch for it. Left out: terms in two
// parameters together other than with the focal factor (two neighbours: some 0.005 px), and kinks
// where a neighbour's approach cuts lit cell points and its retreat adds none (BENCHMARKS
// "Refracting microlenses with errors, corrected"). A lens that this cannot vouch for is measured.

// Corrects the lenses of `out` interpolated from the ideal anchors (interpolated[i]) for their
// errors, as above; the lenses it cannot vouch for go onto `pending` (to be measured). `light`: the
// camera with errors whose light is measured. False when cancelled.
bool correct_for_errors(const PlenopticCamera& light, const Canonical& canonical, const Symmetry& symmetry,
                        const MicroimageOptions& options,
                        const std::vector<Vec2>& at, const std::vector<char>& interpolated, const double range[4],
                        const MicroimageCancel& cancelled, std::vector<MicroimageTruth>& out,
                        std::vector<std::size_t>& pending, MicroimageWork& counts);

} // namespace microimage_detail
} // namespace plenoptic

#endif
