// SPDX-License-Identifier: AGPL-3.0-or-later
// The microlens lattice in the array's own plane: centres, cells, direct lookup, lens types.

#ifndef PLENOPTIC_LATTICE_H
#define PLENOPTIC_LATTICE_H

#include <cstdint>

#include "plenoptic/core/vec.h"

namespace plenoptic {

// The microlens array's grid (None: no array).
enum class GridType { None, Rectangular, Hexagonal };

// Lens indices in the row form of docs/specification.md (section 2):
//   rectangular: centre (k p, l p)
//   hexagonal:   centre ((k + (l mod 2)/2) p, l p sqrt(3)/2)   (odd rows shifted +x by p/2)
struct LensIndex {
    std::int64_t k;
    std::int64_t l;
};

inline bool operator==(LensIndex a, LensIndex b) { return a.k == b.k && a.l == b.l; }
inline bool operator!=(LensIndex a, LensIndex b) { return !(a == b); }

// Lookups clamp indices to this magnitude so that absurd coordinates cannot overflow.
const std::int64_t kMaxLensIndex = std::int64_t(1) << 52;

// Mathematical floor division and modulo, m > 0 (floor_mod is then in [0, m)). Inline so that a
// constant m compiles to shifts and multiplications on the per-ray path.
inline std::int64_t floor_div(std::int64_t a, std::int64_t m)
{
    const std::int64_t q = a / m;
    return (a % m != 0 && a < 0) ? q - 1 : q;
}
inline std::int64_t floor_mod(std::int64_t a, std::int64_t m) { return a - floor_div(a, m) * m; }

// Skew index k_s of a hexagonal lens: centre = k_s (p, 0) + l (p/2, p sqrt(3)/2).
// For rectangular grids skew and row indices are the same.
std::int64_t skew_k(GridType grid, LensIndex lens);
LensIndex from_skew(GridType grid, std::int64_t k_skew, std::int64_t l);

// The lenses whose cells share an edge (or, rectangular, a corner) with the lens's cell: 6 for
// hexagonal grids, 8 for rectangular ones, in the order of (dl, dk) = (-1, -1), (-1, 0), ...,
// (1, 1) in skew indices (the lens itself left out). Returns how many.
int adjacent_lenses(GridType grid, LensIndex lens, LensIndex out[8]);

double row_spacing(GridType grid, double pitch);      // p, or p sqrt(3)/2
double cell_inradius(GridType grid, double pitch);    // p/2 for both grids
double cell_circumradius(GridType grid, double pitch);// p/sqrt(2), or p/sqrt(3)

Vec2 lens_centre(GridType grid, double pitch, LensIndex lens);

// The lens whose cell (Voronoi cell of the lattice) contains (x, y); on a cell border either
// neighbour may be returned. O(1): at most two candidates for hexagonal grids.
LensIndex nearest_lens(GridType grid, double pitch, double x, double y);

// Maps [0,1)^2 uniformly (area-preserving) onto the lens cell, relative to the lens centre;
// (0.5, 0.5) maps to the centre. Rectangular: the square, axis-aligned. Hexagonal: the cell is a
// "pointy-top" hexagon (vertices at top and bottom, flat sides facing +-x); concentric squares
// of the unit square go to concentric hexagons, arc length to arc length.
Vec2 sample_cell_uniform(GridType grid, double pitch, double u1, double u2);

// The inverse of sample_cell_uniform: the (u1, u2) that it maps to the cell point h (relative to
// the lens centre, inside the cell), to rounding.
Vec2 cell_uniform_inverse(GridType grid, double pitch, Vec2 h);

// The ring of the cell's map through the point h (relative to the lens centre): the cell scaled by
// r about its centre has h on its boundary (0 at the centre, 1 on the cell's edge); the square
// ring max(|2 u1 - 1|, |2 u2 - 1|) of the sample that sample_cell_uniform maps to h.
double cell_ring(GridType grid, double pitch, Vec2 h);

// Cell corners relative to the lens centre, counter-clockwise; returns 4 or 6.
int cell_polygon(GridType grid, double pitch, Vec2 corners[6]);

// Multi-focus lens type: with skew index k_s = k - floor(l/2), type = (k_s - l) mod 3,
// so that no two neighbouring lenses share a type. Always 0 when type_count is 1.
int lens_type(LensIndex lens, int type_count);

} // namespace plenoptic

#endif
