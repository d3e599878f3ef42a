// SPDX-License-Identifier: AGPL-3.0-or-later
// The microimage lattice on the sensor and its LFToolbox LensletGridModel.

#include "plenoptic/projection/microimage_lattice.h"

#include <cmath>

#include "plenoptic/camera/rays.h"

namespace plenoptic {

namespace {

// Pixel coordinates (centre convention) of an array-local point projected onto the sensor.
bool local_to_px(const PlenopticCamera& m, Vec2 local, Vec2* px)
{
    const Vec3 c = m.array.to_optics(Vec3{local.x, local.y, 0});
    double x = c.x, y = c.y;
    if (m.lens) {
        // The central projection from the exit pupil's centre e onto the sensor plane.
        const Vec3 e = m.lens->exit_pupil_centre();
        if (!(c.z < e.z))
            return false;
        const double s = (m.sensor.z_mm - e.z) / (c.z - e.z);
        x = e.x + (c.x - e.x) * s;
        y = e.y + (c.y - e.y) * s;
    }
    const PixelPoint p = m.sensor.to_pixel(x, y);
    *px = Vec2{p.u, p.v};
    return is_finite(*px);
}

// x modulo m in [0, m).
double wrap(double x, double m)
{
    const double r = x - m * std::floor(x / m);
    return (r >= m || r < 0) ? 0.0 : r;
}

// LFToolbox's LensletGridModel, normalised the way LFBuildLensletGridModel normalises its own
// estimate: the grid origin's projections on the rotated axes are reduced to [0, HSpacing/2) and
// [0, VSpacing) (1-based pixels), and the row parity decides FirstPosShiftRow. A perfect
// LFToolbox estimate of the rendered white image gives these same numbers.
void fit_lftoolbox(const PlenopticCamera& m, MicroimageLattice* lattice)
{
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    lattice->lftoolbox_valid = false;
    const Vec2 a{lattice->basis_a_px[0], lattice->basis_a_px[1]};
    const Vec2 b{lattice->basis_b_px[0], lattice->basis_b_px[1]};
    const double h_spacing = length(a);
    if (!(h_spacing > 0) || !std::isfinite(h_spacing))
        return;
    // Columns run along +-a, whichever points right; rows go down the image.
    const double column_sign = (a.x > 0 || (a.x == 0 && a.y > 0)) ? 1 : -1;
    const Vec2 e{column_sign * a.x / h_spacing, column_sign * a.y / h_spacing};
    const Vec2 down{-e.y, e.x};
    const double v_spacing = std::fabs(dot(b, down));
    if (!(v_spacing > 0) || !std::isfinite(v_spacing))
        return;
    // Absurdly small microimages: no meaningful grid (and the counts would overflow).
    if (!(W / h_spacing < 1e9 && H / v_spacing < 1e9))
        return;

    const bool hexagonal = m.array.grid == GridType::Hexagonal;
    const Vec2 reference{lattice->origin_px[0] + 1, lattice->origin_px[1] + 1};  // lens (0, 0), 1-based
    double h_proj = dot(reference, e);
    const double v_proj = dot(reference, down);
    // Lens (0, 0) absurdly far outside the image: the row counts below would overflow.
    if (!(std::fabs(v_proj / v_spacing) < 1e15 && std::fabs(h_proj / h_spacing) < 1e15))
        return;
    const double new_v = wrap(v_proj, v_spacing);
    const long long v_steps = std::llround((v_proj - new_v) / v_spacing);
    int shift_row = 0;
    double new_h;
    if (hexagonal) {
        // Rows an odd number of steps away are offset by half a spacing.
        if (v_steps % 2 != 0)
            h_proj += h_spacing / 2;
        new_h = wrap(h_proj, h_spacing / 2);
        const double steps = std::round((h_proj - new_h) / (h_spacing / 2));
        if (!(std::fabs(steps) < 1e15))
            return;  // a grid this fine has no row parity LFToolbox could use
        shift_row = (std::fmod(std::fabs(steps), 2.0) != 0) ? 1 : 2;
    } else {
        new_h = wrap(h_proj, h_spacing);
    }
    const Vec2 offset{new_h * e.x + new_v * down.x, new_h * e.y + new_v * down.y};

    // The lenslet at (row 1, col 1).
    const double first_shift = shift_row == 1 ? h_spacing / 2 : 0.0;
    const double first_u = offset.x + first_shift * e.x - 1, first_v = offset.y + first_shift * e.y - 1;
    const OwnLens first_lookup = own_lens(m, m.sensor.point(first_u + 0.5, first_v + 0.5));
    if (!first_lookup.found)
        return;
    const LensIndex first = first_lookup.lens;
    // As LFBuildLensletGridModel: UMax = floor((W - HOffset) / HSpacing) + 1, likewise VMax;
    // counts beyond 1e15 (absurdly fine grids) are not expressible.
    const double u_max = std::floor((W - offset.x) / h_spacing) + 1;
    const double v_max = std::floor((H - offset.y) / v_spacing) + 1;
    if (!(u_max >= 0 && u_max < 1e15 && v_max >= 0 && v_max < 1e15))
        return;

    lattice->first_lens = first;
    lattice->h_spacing = h_spacing;
    lattice->v_spacing = v_spacing;
    lattice->rot = std::atan2(e.y, e.x);
    lattice->h_offset = offset.x;
    lattice->v_offset = offset.y;
    lattice->first_pos_shift_row = shift_row;
    lattice->u_max = (long long)u_max;
    lattice->v_max = (long long)v_max;
    lattice->lftoolbox_valid = true;
}

} // namespace

MicroimageCentre microimage_centre_px(const PlenopticCamera& m, LensIndex lens)
{
    Vec2 px;
    if (m.array.grid == GridType::None || !local_to_px(m, m.array.lattice_centre_local(lens), &px))
        return MicroimageCentre{0, 0, false};
    return MicroimageCentre{px.x, px.y, true};
}

MicroimageLattice microimage_lattice(const PlenopticCamera& m)
{
    MicroimageLattice lattice = MicroimageLattice();
    lattice.valid = false;
    lattice.lftoolbox_valid = false;
    if (m.array.grid == GridType::None)
        return lattice;
    Vec2 origin;
    if (!local_to_px(m, Vec2{0, 0}, &origin))
        return lattice;
    const double p = m.array.pitch_mm;
    const Vec2 a_local{p, 0};
    const Vec2 b_local = m.array.grid == GridType::Hexagonal ? Vec2{p / 2, row_spacing(m.array.grid, p)} : Vec2{0, p};
    // Central differences at the array centre: exact for an affine map, the tangent map otherwise.
    const double step = 1e-3;
    Vec2 basis[2];
    const Vec2 directions[2] = {a_local, b_local};
    for (int i = 0; i < 2; ++i) {
        Vec2 plus, minus;
        if (!local_to_px(m, step * directions[i], &plus) ||
            !local_to_px(m, (-step) * directions[i], &minus))
            return lattice;
        basis[i] = (0.5 / step) * (plus - minus);
    }
    lattice.valid = true;
    lattice.origin_px[0] = origin.x;
    lattice.origin_px[1] = origin.y;
    lattice.basis_a_px[0] = basis[0].x;
    lattice.basis_a_px[1] = basis[0].y;
    lattice.basis_b_px[0] = basis[1].x;
    lattice.basis_b_px[1] = basis[1].y;
    // Orthogonal projection (no main lens) of any plane is affine; central projection only of a
    // plane parallel to the sensor.
    lattice.exact = !m.lens || !m.array.pose.tilted;
    fit_lftoolbox(m, &lattice);
    return lattice;
}

} // namespace plenoptic
