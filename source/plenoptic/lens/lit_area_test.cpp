// SPDX-License-Identifier: AGPL-3.0-or-later
// The lit-area table of a real lens without an array (lens/lit_area.h), against closed forms
// and a brute-force count that does not use the pupil bounds.

#include <cmath>

#include <gtest/gtest.h>

#include "plenoptic/lens/lit_area.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/pupil_bounds.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {



// Area of the intersection of two discs (radii a, b, centres d apart): the textbook lens formula.
double disc_intersection_area(double a, double b, double d)
{
    if (d >= a + b)
        return 0;
    if (d <= std::fabs(a - b))
        return kPi * std::min(a, b) * std::min(a, b);
    const double alpha = std::acos((d * d + a * a - b * b) / (2 * d * a));
    const double beta = std::acos((d * d + b * b - a * a) / (2 * d * b));
    return a * a * (alpha - std::sin(2 * alpha) / 2) + b * b * (beta - std::sin(2 * beta) / 2);
}

// A weak singlet far in front, then a flat opening of radius a1 (air on both sides: it refracts
// nothing), then, g behind it, the stop of radius s as the last surface: the exit pupil is the stop
// itself, in the plane z = 0. From a sensor point P = (r, 0, -D) a ray through X of the stop's
// plane goes on straight to the opening's plane z = g, where it is P + (X - P)(D + g)/D; it passes
// there when |X - c| <= a1 D / (D + g) with c = r g / (D + g). So the lit area is the intersection
// of the stop's disc with that disc.
const double kStopRadius = 4, kOpeningRadius = 6, kGap = 10;

Prescription vignetting_by_a_front_opening()
{
    Prescription lens;
    lens.surfaces.push_back(LensSurface{400, 3, 1.5, 60, false, 1});
    lens.surfaces.push_back(LensSurface{-400, 20, 1, 60, false, 2});
    lens.surfaces.push_back(LensSurface{0, kGap, 1, 2 * kOpeningRadius, false, 3});
    lens.surfaces.push_back(LensSurface{0, 0, 1, 2 * kStopRadius, true, 4});
    return lens;
}

TEST(LitArea, IntersectionOfTheStopAndAnOpeningsShadow)
{
    const Prescription lens = vignetting_by_a_front_opening();
    const std::shared_ptr<const MainLens> traced = make_prescription_lens(lens, 0, true);
    ASSERT_NEAR(traced->exit_pupil_radius(), kStopRadius, 1e-12);
    const double D = 40;
    const PupilBounds bounds(lens, *traced, -D);
    const LitAreaTable table(*traced, bounds, 0);
    ASSERT_GT(table.size(), 10);
    const double k = (D + kGap) / D;
    // Light stops where the discs part: r g / (D + g) = s + a1 / k.
    const double edge = (kStopRadius + kOpeningRadius / k) / (kGap / (D + kGap));
    EXPECT_NEAR(bounds.field_radius_mm(), edge, 0.05 * edge);
    double worst = 0;
    int vignetted = 0;
    for (double r = 0; r < 1.1 * edge; r += edge / 97) {
        const double expected =
            disc_intersection_area(kStopRadius, kOpeningRadius / k, r * kGap / (D + kGap)) / (kPi * kStopRadius * kStopRadius);
        const double got = table.at(Vec3{r * 0.6, r * 0.8, -D});
        worst = std::max(worst, std::fabs(got - expected));
        vignetted += expected > 0.01 && expected < 0.99;
    }
    EXPECT_GT(vignetted, 40);  // most of the radii lie in the vignetted zone
    // Lattice of 2 x 987 points per radius and linear interpolation between 257 radii: seen 0.0035.
    EXPECT_LT(worst, 0.006) << worst;
}

// The table against a brute-force count on a fine grid over the rear element's whole shadow (no
// pupil bounds), for a triplet whose front and rear elements cut the field into cat's eyes; flat,
// and under irradiance radiometry, where each lit cell counts with the cos^4 law's
// (h^2 + a^2) cos^4(t) / h^2 (the normalisation of camera/radiometry.h, written out here).
void expect_table_matches_brute_force(bool irradiance)
{
    const Prescription lens = test::vignetting_triplet();
    const std::shared_ptr<const MainLens> traced = make_prescription_lens(lens, 0, true);
    const double D = 45;
    const PupilBounds bounds(lens, *traced, -D);
    const double pupil_z = traced->exit_pupil_centre().z;
    const double a = traced->exit_pupil_radius();
    const double h = pupil_z + D;
    const LitAreaTable table(*traced, bounds, irradiance ? h * h + a * a : 0);
    const double pupil_area = kPi * a * a;
    const double rear = 9;  // the rear element's clear radius
    double worst = 0;
    double previous = INFINITY;
    for (double r : {0.0, 3.0, 7.5, 11.0, 14.5, 18.0}) {
        // The rear opening's shadow on the exit pupil's plane, cast from P, with a wide margin.
        const Vec3 p{r, 0, -D};
        const double scale = (pupil_z + D) / D;
        const double cx = r + (0 - r) * scale, half = 1.5 * rear * scale + 2;
        const int n = 600;
        const double cell = 2 * half / n;
        double passing = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const Vec3 x{cx - half + (i + 0.5) * cell, -half + (j + 0.5) * cell, pupil_z};
                if (!traced->to_scene(p, x - p, true).passed)
                    continue;
                const double rho2 = (x.x - p.x) * (x.x - p.x) + (x.y - p.y) * (x.y - p.y);
                const double cos2 = h * h / (h * h + rho2);
                passing += irradiance ? (h * h + a * a) * cos2 * cos2 / (h * h) : 1.0;
            }
        const double expected = passing * cell * cell / pupil_area;
        worst = std::max(worst, std::fabs(table.at(p) - expected));
        if (r == 0) {
            EXPECT_NEAR(expected, 1, 0.02);  // on axis the stop's image is the paraxial pupil, nearly
        }
        if (irradiance) {
            EXPECT_LT(expected, previous);  // the cos^4 law outweighs the pupil's growth off axis
        }
        previous = expected;
    }
    EXPECT_LT(worst, 0.006) << worst;  // seen 0.0017 flat (the grid: 600 x 600 cells)
}

TEST(LitArea, MatchesABruteForceCountThroughATriplet) { expect_table_matches_brute_force(false); }

TEST(LitArea, UnderIrradianceMatchesABruteForceCos4SumThroughATriplet) { expect_table_matches_brute_force(true); }

TEST(LitArea, ZeroBeyondTheField)
{
    const Prescription lens = vignetting_by_a_front_opening();
    const std::shared_ptr<const MainLens> traced = make_prescription_lens(lens, 0, true);
    const PupilBounds bounds(lens, *traced, -40);
    const LitAreaTable table(*traced, bounds, 0);
    EXPECT_EQ(table.at(Vec3{2 * bounds.field_radius_mm(), 0, -40}), 0);
    EXPECT_EQ(table.at(Vec3{NAN, 0, -40}), 0);
}

} // namespace
} // namespace plenoptic
