// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the microlens lattice: direct lookup against brute force, cell sampling, lens types.

#include <cmath>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/core/lattice.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {

// Readable parameter names in test listings.
void PrintTo(GridType grid, std::ostream* out) { *out << (grid == GridType::Hexagonal ? "hexagonal" : "rectangular"); }

namespace {

const double kSqrt3 = std::sqrt(3.0);

double distance_to_centre(GridType grid, double pitch, LensIndex lens, double x, double y)
{
    const Vec2 c = lens_centre(grid, pitch, lens);
    return std::hypot(x - c.x, y - c.y);
}

TEST(Lattice, FloorModAndSkewIndices)
{
    EXPECT_EQ(floor_mod(-1, 2), 1);
    EXPECT_EQ(floor_mod(-3, 3), 0);
    EXPECT_EQ(floor_mod(-4, 3), 2);
    EXPECT_EQ(floor_div(-1, 2), -1);
    EXPECT_EQ(floor_div(-4, 2), -2);
    EXPECT_EQ(floor_div(5, 2), 2);
    const double p = 0.7;
    for (std::int64_t l = -5; l <= 5; ++l) {
        for (std::int64_t ks = -5; ks <= 5; ++ks) {
            const LensIndex lens = from_skew(GridType::Hexagonal, ks, l);
            EXPECT_EQ(skew_k(GridType::Hexagonal, lens), ks);
            const Vec2 c = lens_centre(GridType::Hexagonal, p, lens);
            // centre = ks (p, 0) + l (p/2, p sqrt(3)/2)
            EXPECT_NEAR(c.x, ks * p + l * p / 2, 1e-12) << ks << "," << l;
            EXPECT_NEAR(c.y, l * p * kSqrt3 / 2, 1e-12) << ks << "," << l;
        }
    }
    // Odd rows, negative ones included, are shifted +x by half a pitch.
    EXPECT_DOUBLE_EQ(lens_centre(GridType::Hexagonal, 1.0, LensIndex{0, -1}).x, 0.5);
    EXPECT_DOUBLE_EQ(lens_centre(GridType::Hexagonal, 1.0, LensIndex{0, -2}).x, 0.0);
    EXPECT_DOUBLE_EQ(lens_centre(GridType::Hexagonal, 1.0, LensIndex{2, 3}).x, 2.5);
}

class LatticeLookup : public ::testing::TestWithParam<GridType> {};

TEST_P(LatticeLookup, MatchesBruteForceOn100kPoints)
{
    const GridType grid = GetParam();
    const double pitch = 0.37;
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> coordinate(-50.0, 50.0);
    int mismatches = 0;
    for (int n = 0; n < 100000; ++n) {
        const double x = coordinate(rng), y = coordinate(rng);
        const LensIndex fast = nearest_lens(grid, pitch, x, y);
        const LensIndex slow = test::brute_force_nearest(grid, pitch, x, y);
        const double d_fast = distance_to_centre(grid, pitch, fast, x, y);
        const double d_slow = distance_to_centre(grid, pitch, slow, x, y);
        // Equal lens, or a tie on a cell border.
        if (fast != slow && d_fast > d_slow + 1e-12) {
            ++mismatches;
            ADD_FAILURE() << "(" << x << ", " << y << "): lookup (" << fast.k << ", " << fast.l << ") at " << d_fast
                          << ", brute force (" << slow.k << ", " << slow.l << ") at " << d_slow;
            if (mismatches > 5)
                break;
        }
    }
    EXPECT_EQ(mismatches, 0);
}

TEST_P(LatticeLookup, SampleCellUniformStaysInsideTheCell)
{
    const GridType grid = GetParam();
    const double pitch = 2.0;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const LensIndex lens{3, -5};
    const Vec2 c = lens_centre(grid, pitch, lens);
    for (int n = 0; n < 100000; ++n) {
        const double u1 = unit(rng), u2 = unit(rng);
        const Vec2 offset = sample_cell_uniform(grid, pitch, u1, u2);
        // Shrink slightly so that border points cannot tie with a neighbour.
        const double x = c.x + offset.x * (1 - 1e-9), y = c.y + offset.y * (1 - 1e-9);
        const LensIndex found = nearest_lens(grid, pitch, x, y);
        ASSERT_EQ(found, lens) << "(" << u1 << ", " << u2 << ") -> offset (" << offset.x << ", " << offset.y
                               << ") left the cell";
    }
    const Vec2 centre = sample_cell_uniform(grid, pitch, 0.5, 0.5);
    EXPECT_EQ(centre.x, 0.0);
    EXPECT_EQ(centre.y, 0.0);
}

TEST_P(LatticeLookup, SampleCellUniformIsUniform)
{
    // Chi-square test over a grid of boxes, expected counts from the box's area inside the cell
    // (integrated on a fine grid with the lattice lookup as the membership test).
    const GridType grid = GetParam();
    const double pitch = 1.0;
    const int bins = 8;
    const double half = pitch / 2, top = cell_circumradius(grid, pitch);
    const double x0 = -half, y0 = grid == GridType::Hexagonal ? -top : -half;
    const double bw = 2 * half / bins, bh = -2 * y0 / bins;
    std::vector<double> area(bins * bins, 0.0);
    const int fine = 400;
    double total_area = 0;
    for (int a = 0; a < fine * bins; ++a) {
        for (int b = 0; b < fine * bins; ++b) {
            const double x = x0 + (a + 0.5) * bw / fine, y = y0 + (b + 0.5) * bh / fine;
            if (nearest_lens(grid, pitch, x, y) == LensIndex{0, 0}) {
                area[(a / fine) * bins + b / fine] += 1;
                total_area += 1;
            }
        }
    }
    const int samples = 200000;
    std::vector<double> count(bins * bins, 0.0);
    std::mt19937_64 rng(99);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int n = 0; n < samples; ++n) {
        const Vec2 o = sample_cell_uniform(grid, pitch, unit(rng), unit(rng));
        int a = int((o.x - x0) / bw), b = int((o.y - y0) / bh);
        a = std::min(std::max(a, 0), bins - 1);
        b = std::min(std::max(b, 0), bins - 1);
        count[a * bins + b] += 1;
    }
    double chi2 = 0;
    int dof = -1;
    for (int i = 0; i < bins * bins; ++i) {
        const double expected = samples * area[i] / total_area;
        if (expected < 20)
            continue;  // boxes barely touching the cell: their count is dominated by discretisation
        chi2 += (count[i] - expected) * (count[i] - expected) / expected;
        ++dof;
    }
    // Far above the 99.9% quantile for ~60 degrees of freedom (~99) would mean non-uniform.
    EXPECT_LT(chi2, 2.0 * dof + 40) << "chi-square " << chi2 << " over " << dof << " degrees of freedom";
    // And the total area is the cell's: p^2 or (sqrt(3)/2) p^2.
    const double cell_area = total_area * (bw / fine) * (bh / fine);
    EXPECT_NEAR(cell_area, grid == GridType::Hexagonal ? kSqrt3 / 2 : 1.0, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(BothGrids, LatticeLookup, ::testing::Values(GridType::Rectangular, GridType::Hexagonal),
                         [](const ::testing::TestParamInfo<GridType>& info) {
                             return std::string(info.param == GridType::Hexagonal ? "Hexagonal" : "Rectangular");
                         });

// The inverse of the cell map: back to the sample it came from; and the ring through a point is where
// the cell, scaled about its centre, has that point on its edge (found by the lattice lookup).
TEST_P(LatticeLookup, CellMapInvertsAndRingsAreScaledCells)
{
    const GridType grid = GetParam();
    const double p = 0.014;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (int i = 0; i < 2000; ++i) {
        const double u = i < 576 ? (i % 24 + 0.5) / 24 : uniform(rng), v = i < 576 ? (i / 24 + 0.5) / 24 : uniform(rng);
        const Vec2 h = sample_cell_uniform(grid, p, u, v);
        const Vec2 back = cell_uniform_inverse(grid, p, h);
        EXPECT_NEAR(back.x, u, 1e-12) << u << ", " << v;
        EXPECT_NEAR(back.y, v, 1e-12) << u << ", " << v;
        const double ring = cell_ring(grid, p, h);
        EXPECT_NEAR(ring, std::fmax(std::fabs(2 * u - 1), std::fabs(2 * v - 1)), 1e-12);
        if (ring < 1e-3)
            continue;
        const Vec2 edge{h.x / ring, h.y / ring};
        EXPECT_EQ(nearest_lens(grid, p, (1 - 1e-9) * edge.x, (1 - 1e-9) * edge.y), (LensIndex{0, 0}));
        EXPECT_NE(nearest_lens(grid, p, (1 + 1e-9) * edge.x, (1 + 1e-9) * edge.y), (LensIndex{0, 0}));
    }
}

TEST(Lattice, HexagonalCellIsPointyTop)
{
    const double p = 1.0, R = p / kSqrt3;
    // Straight up, the cell reaches its circumradius; sideways only the inradius.
    EXPECT_EQ(nearest_lens(GridType::Hexagonal, p, 0, 0.99 * R), (LensIndex{0, 0}));
    EXPECT_NE(nearest_lens(GridType::Hexagonal, p, 0, 1.01 * R), (LensIndex{0, 0}));
    EXPECT_EQ(nearest_lens(GridType::Hexagonal, p, 0.499 * p, 0), (LensIndex{0, 0}));
    EXPECT_NE(nearest_lens(GridType::Hexagonal, p, 0.501 * p, 0), (LensIndex{0, 0}));
    // Each corner is equidistant from the three centres around it.
    Vec2 corner[6];
    ASSERT_EQ(cell_polygon(GridType::Hexagonal, p, corner), 6);
    for (int i = 0; i < 6; ++i) {
        EXPECT_NEAR(std::hypot(corner[i].x, corner[i].y), R, 1e-12);
        int at_distance = 0;
        for (int l = -2; l <= 2; ++l)
            for (int k = -2; k <= 2; ++k)
                if (std::fabs(distance_to_centre(GridType::Hexagonal, p, LensIndex{k, l}, corner[i].x, corner[i].y) - R) < 1e-9)
                    ++at_distance;
        EXPECT_EQ(at_distance, 3) << "corner " << i << " (" << corner[i].x << ", " << corner[i].y << ")";
    }
    EXPECT_NEAR(cell_inradius(GridType::Hexagonal, p), 0.5, 1e-15);
}

TEST(Lattice, MultiFocusNeighboursNeverShareAType)
{
    const double p = 1.0;
    int seen[3] = {0, 0, 0};
    for (int l = -20; l <= 20; ++l) {
        for (int k = -20; k <= 20; ++k) {
            const LensIndex lens{k, l};
            const int type = lens_type(lens, 3);
            ASSERT_GE(type, 0);
            ASSERT_LT(type, 3);
            ++seen[type];
            // The metadata's rule: (k_skew - l) mod 3.
            EXPECT_EQ(type, int(floor_mod(skew_k(GridType::Hexagonal, lens) - l, 3)));
            int neighbours = 0;
            for (int dl = -1; dl <= 1; ++dl) {
                for (int dk = -1; dk <= 1; ++dk) {
                    const LensIndex other{k + dk, l + dl};
                    const Vec2 a = lens_centre(GridType::Hexagonal, p, lens);
                    const Vec2 b = lens_centre(GridType::Hexagonal, p, other);
                    if (std::fabs(std::hypot(a.x - b.x, a.y - b.y) - p) > 1e-9)
                        continue;  // not a neighbour
                    ++neighbours;
                    EXPECT_NE(lens_type(other, 3), type)
                        << "lenses (" << k << "," << l << ") and (" << other.k << "," << other.l << ") share type " << type;
                }
            }
            EXPECT_EQ(neighbours, 6) << k << "," << l;
        }
    }
    EXPECT_GT(seen[0], 500);
    EXPECT_GT(seen[1], 500);
    EXPECT_GT(seen[2], 500);
    EXPECT_EQ(lens_type(LensIndex{5, 7}, 1), 0);
}

TEST(Lattice, AbsurdCoordinatesDoNotOverflow)
{
    const LensIndex a = nearest_lens(GridType::Hexagonal, 1e-300, 1e300, -1e300);
    EXPECT_LE(a.k, kMaxLensIndex);
    EXPECT_GE(a.l, -kMaxLensIndex);
    const LensIndex b = nearest_lens(GridType::Rectangular, 1.0, NAN, INFINITY);
    EXPECT_EQ(b.k, 0);
    EXPECT_EQ(b.l, kMaxLensIndex);
}

} // namespace
} // namespace plenoptic
