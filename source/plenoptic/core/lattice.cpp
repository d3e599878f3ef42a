// SPDX-License-Identifier: AGPL-3.0-or-later
// The microlens lattice: O(1) lens lookup, cell shapes, uniform cell sampling, lens types.

#include "plenoptic/core/lattice.h"

#include <algorithm>
#include <cmath>

namespace plenoptic {

namespace {

const double kSqrt3 = 1.7320508075688772935;

// Rounds a lattice coordinate to an index, clamping so that the conversion is defined.
std::int64_t to_index(double value)
{
    if (!(value == value))
        return 0;  // NaN: any lens will do, the caller rejects the non-finite ray later
    const double limit = double(kMaxLensIndex);
    if (value > limit)
        return kMaxLensIndex;
    if (value < -limit)
        return -kMaxLensIndex;
    return std::int64_t(value);
}

std::int64_t round_to_index(double value) { return to_index(std::floor(value + 0.5)); }

bool is_odd(std::int64_t l) { return (l & 1) != 0; }  // two's complement: -1 is odd too

} // namespace

std::int64_t skew_k(GridType grid, LensIndex lens)
{
    return grid == GridType::Hexagonal ? lens.k - floor_div(lens.l, 2) : lens.k;
}

LensIndex from_skew(GridType grid, std::int64_t k_skew, std::int64_t l)
{
    return grid == GridType::Hexagonal ? LensIndex{k_skew + floor_div(l, 2), l} : LensIndex{k_skew, l};
}

int adjacent_lenses(GridType grid, LensIndex lens, LensIndex out[8])
{
    const std::int64_t skew = skew_k(grid, lens);
    int count = 0;
    for (int dl = -1; dl <= 1; ++dl)
        for (int dk = -1; dk <= 1; ++dk) {
            if ((dk == 0 && dl == 0) || (grid == GridType::Hexagonal && (dk + dl > 1 || dk + dl < -1)))
                continue;  // the lens itself, or not adjacent in skew indices
            out[count++] = from_skew(grid, skew + dk, lens.l + dl);
        }
    return count;
}

double row_spacing(GridType grid, double pitch)
{
    return grid == GridType::Hexagonal ? pitch * (kSqrt3 / 2) : pitch;
}

double cell_inradius(GridType, double pitch) { return pitch / 2; }

double cell_circumradius(GridType grid, double pitch)
{
    return grid == GridType::Hexagonal ? pitch / kSqrt3 : pitch / std::sqrt(2.0);
}

Vec2 lens_centre(GridType grid, double pitch, LensIndex lens)
{
    if (grid == GridType::Hexagonal) {
        const double shift = is_odd(lens.l) ? 0.5 : 0.0;
        return Vec2{(double(lens.k) + shift) * pitch, double(lens.l) * row_spacing(grid, pitch)};
    }
    return Vec2{double(lens.k) * pitch, double(lens.l) * pitch};
}

LensIndex nearest_lens(GridType grid, double pitch, double x, double y)
{
    if (grid != GridType::Hexagonal)
        return LensIndex{round_to_index(x / pitch), round_to_index(y / pitch)};

    // The nearest centre lies in one of the two rows bracketing y: a row further away is at
    // least one row spacing (p sqrt(3)/2) off, more than the p/2 reach of the nearer rows.
    const std::int64_t below = to_index(std::floor(y / row_spacing(grid, pitch)));
    LensIndex best{0, 0};
    double best_d2 = 0;
    for (int row = 0; row < 2; ++row) {
        const std::int64_t l = below + row;
        const double shift = is_odd(l) ? 0.5 : 0.0;
        const LensIndex candidate{round_to_index(x / pitch - shift), l};
        const Vec2 c = lens_centre(grid, pitch, candidate);
        const double d2 = (x - c.x) * (x - c.x) + (y - c.y) * (y - c.y);
        if (row == 0 || d2 < best_d2) {
            best = candidate;
            best_d2 = d2;
        }
    }
    return best;
}

Vec2 sample_cell_uniform(GridType grid, double pitch, double u1, double u2)
{
    if (grid != GridType::Hexagonal)
        return Vec2{(u1 - 0.5) * pitch, (u2 - 0.5) * pitch};

    // Concentric square rings (L-infinity radius r) go to concentric hexagon rings
    // (inradius r p/2); the arc-length fraction t along the ring is kept. Both ring families
    // have area element d(radius) * d(arc), and arc lengths scale by a constant, so the map
    // is area-preserving up to a constant factor.
    const double a = 2 * u1 - 1;
    const double b = 2 * u2 - 1;
    const double r = std::fmax(std::fabs(a), std::fabs(b));
    if (r == 0)
        return Vec2{0, 0};

    // Arc length s along the square ring, counter-clockwise from (r, 0); perimeter 8r.
    double s;
    if (std::fabs(a) >= std::fabs(b))
        s = a > 0 ? (b >= 0 ? b : 8 * r + b) : 4 * r - b;
    else
        s = b > 0 ? 2 * r - a : 6 * r + a;
    const double t = s / (8 * r);

    // Same fraction along the hexagon ring, counter-clockwise from the middle of its right
    // side. Corners of the unit-inradius hexagon, from the one at -30 degrees.
    static const Vec2 corner[6] = {
        {1, -1 / kSqrt3}, {1, 1 / kSqrt3}, {0, 2 / kSqrt3},
        {-1, 1 / kSqrt3}, {-1, -1 / kSqrt3}, {0, -2 / kSqrt3}};
    double sides = 6 * t + 0.5;  // in side lengths from the corner at -30 degrees
    if (sides >= 6)
        sides -= 6;
    int edge = int(sides);
    if (edge > 5)
        edge = 5;
    const double along = sides - edge;
    const Vec2 from = corner[edge];
    const Vec2 to = corner[(edge + 1) % 6];
    const double inradius = r * pitch / 2;
    return Vec2{inradius * (from.x + along * (to.x - from.x)), inradius * (from.y + along * (to.y - from.y))};
}

double cell_ring(GridType grid, double pitch, Vec2 h)
{
    const double x = std::fabs(h.x) / (0.5 * pitch), y = std::fabs(h.y) / (0.5 * pitch);
    if (grid != GridType::Hexagonal)
        return std::fmax(x, y);
    // The largest distance to the lines through the centre along the sides (normals at 0 and +-60
    // degrees), over the inradius.
    return std::fmax(x, 0.5 * x + 0.5 * kSqrt3 * y);
}

Vec2 cell_uniform_inverse(GridType grid, double pitch, Vec2 h)
{
    if (grid != GridType::Hexagonal)
        return Vec2{h.x / pitch + 0.5, h.y / pitch + 0.5};
    const double r = cell_ring(grid, pitch, h);
    if (r == 0)
        return Vec2{0.5, 0.5};
    // The side of the ring the point lies on (side e runs from the corner at -30 + 60 e degrees to
    // the next), where along it, and so the fraction t of the ring from the middle of its right side.
    static const Vec2 corner[6] = {
        {1, -1 / kSqrt3}, {1, 1 / kSqrt3}, {0, 2 / kSqrt3}, {-1, 1 / kSqrt3}, {-1, -1 / kSqrt3}, {0, -2 / kSqrt3}};
    double turns = (std::atan2(h.y, h.x) + kPi / 6) / (kPi / 3);
    if (turns < 0)
        turns += 6;
    const int edge = std::min(5, int(turns));
    const Vec2 from = corner[edge], to = corner[(edge + 1) % 6];
    const double px = h.x / (0.5 * pitch * r), py = h.y / (0.5 * pitch * r);
    const double ex = to.x - from.x, ey = to.y - from.y;
    const double along = std::fmin(1.0, std::fmax(0.0, ((px - from.x) * ex + (py - from.y) * ey) / (ex * ex + ey * ey)));
    double t = (edge + along - 0.5) / 6;
    if (t < 0)
        t += 1;
    // The same fraction of the square ring of L-infinity radius r, counter-clockwise from (r, 0).
    const double s = 8 * r * t;
    double a, b;
    if (s < r) {
        a = r;
        b = s;
    } else if (s < 3 * r) {
        a = 2 * r - s;
        b = r;
    } else if (s < 5 * r) {
        a = -r;
        b = 4 * r - s;
    } else if (s < 7 * r) {
        a = s - 6 * r;
        b = -r;
    } else {
        a = r;
        b = s - 8 * r;
    }
    return Vec2{0.5 * (a + 1), 0.5 * (b + 1)};
}

int cell_polygon(GridType grid, double pitch, Vec2 corners[6])
{
    const double h = pitch / 2;
    if (grid != GridType::Hexagonal) {
        corners[0] = Vec2{h, -h};
        corners[1] = Vec2{h, h};
        corners[2] = Vec2{-h, h};
        corners[3] = Vec2{-h, -h};
        return 4;
    }
    const double R = pitch / kSqrt3;  // circumradius: corners at top and bottom
    corners[0] = Vec2{h, -R / 2};
    corners[1] = Vec2{h, R / 2};
    corners[2] = Vec2{0, R};
    corners[3] = Vec2{-h, R / 2};
    corners[4] = Vec2{-h, -R / 2};
    corners[5] = Vec2{0, -R};
    return 6;
}

int lens_type(LensIndex lens, int type_count)
{
    if (type_count != 3)
        return 0;
    const std::int64_t k_skew = lens.k - floor_div(lens.l, 2);
    return int(floor_mod(k_skew - lens.l, 3));
}

} // namespace plenoptic
