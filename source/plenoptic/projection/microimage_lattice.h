// SPDX-License-Identifier: AGPL-3.0-or-later
// The microimage lattice on the sensor (centres of the microimages) and its LFToolbox form.

#ifndef PLENOPTIC_MICROIMAGE_LATTICE_H
#define PLENOPTIC_MICROIMAGE_LATTICE_H

#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// A microimage centre in pixels (centre convention); valid false when there is none (no array, or
// the projection is not finite).
struct MicroimageCentre {
    double u, v;
    bool valid;
};

// Centre of lens `lens`'s microimage in pixels (centre convention): the central projection of the
// posed lens centre from the main-lens centre onto the sensor (orthogonal without main lens); with
// manufacturing errors, of its lattice point (where an ideal array has it).
MicroimageCentre microimage_centre_px(const PlenopticCamera& model, LensIndex lens);

// The microimage-centre lattice in pixel coordinates (centre convention) and its LFToolbox form.
// centre(k_s, l) = origin + k_s a + l b in skew indices (a = (p, 0); b = (p/2, p sqrt(3)/2)
// hexagonal, (0, p) rectangular). Exact (up to rounding) for arrays not tilted about x or y;
// otherwise a and b are the affine map at the array centre (exact = false) while the origin is
// still exact.
struct MicroimageLattice {
    bool valid;              // false without array
    double origin_px[2];
    double basis_a_px[2];
    double basis_b_px[2];
    bool exact;
    // LFToolbox LensletGridModel, 1-based MATLAB pixels (first pixel's centre at (1, 1)).
    // Its grid: uu = col * HSpacing (+ HSpacing/2 on 1-based rows FirstPosShiftRow:2:end),
    // vv = row * VSpacing, rotated by [cos -sin; sin cos](Rot), plus (HOffset, VOffset).
    // Normalised as LFToolbox's LFBuildLensletGridModel normalises its estimate: the origin's
    // projections on the rotated axes lie in [0, HSpacing/2) and [0, VSpacing), so (row 1, col 1)
    // is the top-left lenslet of the first row (first_lens) and the origin is that lenslet
    // (FirstPosShiftRow 2) or half a spacing left of it (FirstPosShiftRow 1); UMax and VMax as
    // LFToolbox computes them. Exact for square pixels and no tilt about x or y; otherwise derived
    // from the basis vectors above.
    bool lftoolbox_valid;
    double h_spacing, v_spacing, h_offset, v_offset, rot;
    int first_pos_shift_row; // 1 or 2 for hexagonal grids; 0 for rectangular (LFToolbox cannot express it)
    long long u_max, v_max;
    LensIndex first_lens;    // the lenslet at LFToolbox's (row 1, col 1), row form
};

MicroimageLattice microimage_lattice(const PlenopticCamera& model);

} // namespace plenoptic

#endif
