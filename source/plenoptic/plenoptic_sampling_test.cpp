// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of camera samples, the concentric disc map and the chi-square quantiles.

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic_sampling.h"

namespace plenoptic {
namespace {

TEST(Sampling, SingleSampleIsPixelAndApertureCentre)
{
    for (int i : {0, 7, 1000}) {
        const CameraSample s = make_sample(i, 3, 0, 1);
        EXPECT_EQ(s.pixel_u, 0.5);
        EXPECT_EQ(s.pixel_v, 0.5);
        EXPECT_EQ(s.lens_u, 0.5);
        EXPECT_EQ(s.lens_v, 0.5);
    }
}

TEST(Sampling, DeterministicAndInRange)
{
    for (int n = 0; n < 64; ++n) {
        const CameraSample a = make_sample(12, 34, n, 64);
        const CameraSample b = make_sample(12, 34, n, 64);
        EXPECT_EQ(a.pixel_u, b.pixel_u);
        EXPECT_EQ(a.pixel_v, b.pixel_v);
        EXPECT_EQ(a.lens_u, b.lens_u);
        EXPECT_EQ(a.lens_v, b.lens_v);
        for (double v : {a.pixel_u, a.pixel_v, a.lens_u, a.lens_v}) {
            EXPECT_GE(v, 0.0);
            EXPECT_LT(v, 1.0);
        }
    }
    // Neighbouring pixels get different rotations.
    const CameraSample a = make_sample(12, 34, 0, 64);
    const CameraSample b = make_sample(13, 34, 0, 64);
    const CameraSample c = make_sample(12, 35, 0, 64);
    EXPECT_NE(a.pixel_u, b.pixel_u);
    EXPECT_NE(a.lens_u, c.lens_u);
    // Negative indices are fine too (hash of the bit pattern).
    const CameraSample d = make_sample(-1, -1, 5, 16);
    EXPECT_GE(d.lens_v, 0.0);
    EXPECT_LT(d.lens_v, 1.0);
}

TEST(Sampling, LowDiscrepancyInEachDimension)
{
    // 64 samples of one pixel: each eighth of [0,1) gets close to 8 in every dimension,
    // far tighter than independent random numbers would.
    for (int pixel = 0; pixel < 20; ++pixel) {
        int bins[4][8] = {};
        for (int n = 0; n < 64; ++n) {
            const CameraSample s = make_sample(pixel, 2 * pixel + 1, n, 64);
            const double v[4] = {s.pixel_u, s.pixel_v, s.lens_u, s.lens_v};
            for (int d = 0; d < 4; ++d)
                ++bins[d][int(v[d] * 8)];
        }
        for (int d = 0; d < 4; ++d)
            for (int b = 0; b < 8; ++b)
                EXPECT_NEAR(bins[d][b], 8, 3) << "pixel " << pixel << " dimension " << d << " bin " << b;
    }
}

TEST(Sampling, ConcentricDiscCentreAndUniformity)
{
    const Vec2 c = concentric_disc(0.5, 0.5);
    EXPECT_EQ(c.x, 0.0);
    EXPECT_EQ(c.y, 0.0);
    // Edge midpoints go to the circle.
    EXPECT_NEAR(length(concentric_disc(1.0, 0.5)), 1.0, 1e-15);
    EXPECT_NEAR(length(concentric_disc(0.5, 0.0)), 1.0, 1e-15);
    // A grid of inputs: inside the disc, a quarter within radius 1/2, equal quadrants.
    const int n = 400;
    int inner = 0, quadrant[4] = {0, 0, 0, 0};
    for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
            const Vec2 p = concentric_disc((a + 0.5) / n, (b + 0.5) / n);
            ASSERT_LE(length(p), 1.0 + 1e-12);
            if (length(p) < 0.5)
                ++inner;
            ++quadrant[(p.x >= 0 ? 0 : 1) + (p.y >= 0 ? 0 : 2)];
        }
    }
    EXPECT_NEAR(double(inner) / (n * n), 0.25, 0.005);
    for (int q = 0; q < 4; ++q)
        EXPECT_NEAR(double(quadrant[q]) / (n * n), 0.25, 0.005) << "quadrant " << q;
}

struct QuantileCase {
    double p, dof, expected;
};

TEST(Sampling, ChiSquareQuantilesMatchKnownValues)
{
    // Reference values computed with arbitrary precision (mpmath).
    const QuantileCase cases[] = {
        {0.9, 1, 2.70554345409541},   {0.9, 10, 15.9871791721053}, {0.1, 1, 0.0157907740934312},
        {0.95, 5, 11.0704976935164},  {0.5, 2, 1.38629436111989},  {0.1, 63, 49.1105386750008},
        {0.99, 3, 11.3448667301444},  {0.1, 4, 1.06362321677922},  {0.1, 1000, 943.132562342892},
        {0.9, 1001, 1058.75255912598}, {0.1, 5000, 4872.28071847441},
    };
    for (const QuantileCase& c : cases) {
        const double tolerance = c.dof > kExactChi2Dof ? 1e-5 * c.expected : 1e-9 * c.expected;
        EXPECT_NEAR(chi2_quantile(c.p, c.dof), c.expected, tolerance) << "p " << c.p << " dof " << c.dof;
    }
    // cephes' chdtri, which POV-Ray uses, is the upper-tail inverse.
    EXPECT_NEAR(chi2_upper_quantile(0.9, 1), 0.0157907740934312, 1e-12);
    EXPECT_NEAR(regularized_lower_gamma(1.0, 2.0), 1 - std::exp(-2.0), 1e-13);
    EXPECT_NEAR(log_gamma(0.5), 0.5 * std::log(3.14159265358979323846), 1e-13);
    EXPECT_NEAR(log_gamma(10), std::log(362880.0), 1e-12);
}

TEST(Sampling, AdaptiveThresholdsAsFocalBlur)
{
    const double variance = 1.0 / 128;
    const std::vector<double> t = adaptive_thresholds(64, 0.9, variance);
    ASSERT_EQ(t.size(), 64u);
    // threshold[n-1] = variance * chdtri(n, c) / chdtri(max - 1, c): equal to variance at n = max - 1.
    EXPECT_NEAR(t[62], variance, 1e-15);
    EXPECT_NEAR(t[0], variance * 0.0157907740934312 / 49.1105386750008, 1e-12);
    for (size_t n = 1; n < t.size(); ++n)
        EXPECT_GT(t[n], t[n - 1]) << n;
    const std::vector<double> one = adaptive_thresholds(1, 0.9, variance);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0], 0.0);
    // A million-sample table is quick and finite.
    const std::vector<double> big = adaptive_thresholds(1000000, 0.9, variance);
    EXPECT_NEAR(big[999998], variance, 1e-12);
    EXPECT_TRUE(std::isfinite(big[999999]));
}

} // namespace
} // namespace plenoptic
