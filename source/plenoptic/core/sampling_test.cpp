// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of camera samples, the concentric disc map, the chi-square quantiles and the adaptive
// thresholds.

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/core/sampling.h"

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
    double q, dof, expected;
};

TEST(Sampling, ChiSquareUpperQuantilesMatchScipy)
{
    // The x with P(chi2_dof > x) = q, from SciPy 1.10.1 (Debian's python3-scipy):
    //   /usr/bin/python3 -c "from scipy.stats import chi2; print(repr(chi2.isf(q, dof)))"
    const QuantileCase cases[] = {
        {0.9, 1, 0.015790774093431225},
        {0.9, 2, 0.21072103131565256},
        {0.9, 3, 0.58437437415518312},
        {0.9, 4, 1.0636232167792237},
        {0.9, 10, 4.8651820519253297},
        {0.1, 1, 2.70554345409542},
        {0.1, 10, 15.987179172105261},
        {0.05, 5, 11.070497693516355},
        {0.5, 2, 1.386294361119891},
        {0.9, 63, 49.110538675000782},
        {0.01, 3, 11.344866730144368},
        {0.9, 1000, 943.13256234289202},
        {0.1, 1001, 1058.7525591259778},
        {0.9, 5000, 4872.2807184744124},
        {0.9, 10000, 9819.19488184482},
        {1e-09, 1, 37.324893051362324},
        {0.999999999, 1, 1.5707962379445853e-18},
        {1e-09, 10000, 10871.668312781652},
        {0.999999999, 10000, 9174.9592047974184},
        {0.999, 0.5, 1.3499395786230751e-12},
    };
    for (const QuantileCase& c : cases)
        EXPECT_NEAR(chi2_upper_quantile(c.q, c.dof), c.expected, 1e-12 * c.expected) << "q " << c.q << " dof " << c.dof;
    // Outside (0, 1): the limits, no exception.
    EXPECT_EQ(chi2_upper_quantile(0, 3), std::numeric_limits<double>::infinity());
    EXPECT_EQ(chi2_upper_quantile(1, 3), 0.0);
    EXPECT_EQ(chi2_upper_quantile(std::nan(""), 3), std::numeric_limits<double>::infinity());
}

// POV-Ray's focal_blur (source/backend/render/tracepixel.cpp, POV-Ray 3.7.0.10):
//   T1 = camera.Variance / chdtri(camera.Blur_Samples - 1, camera.Confidence);
//   Sample_Threshold[i] = T1 * chdtri(i + 1, camera.Confidence);   i = 0 .. Blur_Samples - 1
// with chdtri(df, y) the x with P(chi2_df > x) = y. The quantiles below are SciPy's
//   /usr/bin/python3 -c "from scipy.stats import chi2; print(repr(chi2.isf(0.9, n)))"
// (POV-Ray 3.7's own chdtri is up to 8% off at odd df below 27, where its lgam is wrong for
// half-integers: chdtri(1, 0.9) = 0.0170987 there. The thresholds follow the formula with the
// exact quantiles, as they did before Boost.Math.)
double pov_threshold(double variance, double chdtri_n, double chdtri_max_minus_1)
{
    const double T1 = variance / chdtri_max_minus_1;
    return T1 * chdtri_n;
}

TEST(Sampling, AdaptiveThresholdsAsFocalBlur)
{
    const double variance = 1.0 / 128;
    const std::vector<double> t = adaptive_thresholds(64, 0.9, variance);
    ASSERT_EQ(t.size(), 64u);
    const double chdtri_63 = 49.110538675000782;
    const struct {
        int n;
        double chdtri;
    } table[] = {{1, 0.015790774093431225}, {2, 0.21072103131565256}, {3, 0.5843743741551831},
                 {7, 2.833106917815344},    {31, 21.43356450031078},  {62, 48.22570600047236},
                 {63, 49.11053867500078},   {64, 49.99629021343765}};
    for (const auto& row : table) {
        const double expected = pov_threshold(variance, row.chdtri, chdtri_63);
        EXPECT_NEAR(t[row.n - 1], expected, 1e-12 * expected) << "n " << row.n;
    }
    EXPECT_NEAR(t[62], variance, 1e-15);
    for (size_t n = 1; n < t.size(); ++n)
        EXPECT_GT(t[n], t[n - 1]) << n;
    const std::vector<double> one = adaptive_thresholds(1, 0.9, variance);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one[0], 0.0);
}

TEST(Sampling, AdaptiveThresholdsBeyondTheExactRange)
{
    // Above kExactChi2Dof degrees of freedom the quantiles are Wilson-Hilferty's: within 2e-7
    // of the exact ones at confidence 0.9 (and the table stays quick and monotonic).
    ASSERT_EQ(kExactChi2Dof, 10000);
    const double variance = 1.0 / 128;
    const std::vector<double> t = adaptive_thresholds(100001, 0.9, variance);
    ASSERT_EQ(t.size(), 100001u);
    const double chdtri_100000 = 99427.30267187666;
    const struct {
        int n;
        double chdtri;
        double tolerance;
    } table[] = {{1, 0.015790774093431225, 1e-12},     {9999, 9818.20394427897, 1e-12},
                 {10000, 9819.19488184482, 1e-12},     {10001, 9820.185819863806, 2e-7},
                 {12345, 12144.062240739002, 2e-7},    {99999, 99426.30553752878, 2e-7},
                 {100000, 99427.30267187666, 2e-7}};
    for (const auto& row : table) {
        const double expected = pov_threshold(variance, row.chdtri, chdtri_100000);
        // The table's scale comes from the approximated chdtri(100000): 2e-7 everywhere above.
        const double tolerance = row.n > kExactChi2Dof ? 2e-7 : 2e-7 + row.tolerance;
        EXPECT_NEAR(t[row.n - 1], expected, tolerance * expected) << "n " << row.n;
    }
    for (size_t n = 1; n < t.size(); ++n)
        ASSERT_GT(t[n], t[n - 1]) << n;
    // A million-sample table is quick and finite.
    const std::vector<double> big = adaptive_thresholds(1000000, 0.9, variance);
    EXPECT_NEAR(big[999998], variance, 1e-12);
    EXPECT_TRUE(std::isfinite(big[999999]));
    // Extreme confidences stay finite and increasing across the switch to Wilson-Hilferty.
    for (double confidence : {1e-9, 0.5, 1 - 1e-9}) {
        const std::vector<double> e = adaptive_thresholds(20000, confidence, variance);
        for (size_t n = 1; n < e.size(); ++n)
            ASSERT_GT(e[n], e[n - 1]) << "confidence " << confidence << " n " << n;
        EXPECT_TRUE(std::isfinite(e.back()));
    }
}

} // namespace
} // namespace plenoptic
