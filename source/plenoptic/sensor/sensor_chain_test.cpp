// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor model (sensor/sensor_chain.h) against Poisson and Gaussian statistics, the Bayer
// patterns' names, and its own determinism.

#include <cmath>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/sensor/sensor_chain.h"

namespace plenoptic {
namespace {

// Mean and variance of the DN of n sites of one value.
struct Moments {
    double mean, variance;
};

Moments moments(const SensorChainParams& c, double value, int n, int channel = 1)
{
    double sum = 0, sum_sq = 0;
    for (int k = 0; k < n; ++k) {
        const double dn = sensor_dn(c, value, std::uint64_t(k), channel);
        sum += dn;
        sum_sq += dn * dn;
    }
    const double mean = sum / n;
    return Moments{mean, (sum_sq - n * mean * mean) / (n - 1)};
}

// One DN per electron: 16 bits, no black level, a full well of 65535 electrons.
SensorChainParams unit_gain()
{
    SensorChainParams c;
    c.given = true;
    c.bit_depth = 16;
    c.full_well_e = 65535;
    c.has_exposure = true;
    c.exposure_e = 100;
    return c;
}

TEST(SensorChain, BayerSitesFollowThePatternsName)
{
    // The name lists the 2 x 2 cell's colours: top-left, top-right, bottom-left, bottom-right.
    for (BayerPattern p : {BayerPattern::RGGB, BayerPattern::BGGR, BayerPattern::GRBG, BayerPattern::GBRG}) {
        const char* name = bayer_name(p);
        ASSERT_EQ(std::strlen(name), 4u);
        for (int j = 0; j < 6; ++j)
            for (int i = 0; i < 6; ++i) {
                const char letter = name[(j % 2) * 2 + (i % 2)];
                EXPECT_EQ(bayer_channel(p, i, j), letter == 'r' ? 0 : letter == 'g' ? 1 : 2) << name << " " << i << "," << j;
            }
    }
}

TEST(SensorChain, ShotNoiseIsPoisson)
{
    // Mean and variance of a Poisson count are both its mean; over n sites the sample mean has a
    // standard error sqrt(mu / n) and the sample variance sqrt((mu + 2 mu^2) / n) (its fourth
    // central moment is mu + 3 mu^2): 5 of those are allowed. Means on both sides of 10, where the
    // Poisson sampler changes method, and a deep one.
    SensorChainParams c = unit_gain();
    const int n = 200000;
    for (double mu : {0.3, 4.0, 9.5, 10.5, 60.0, 2500.0}) {
        const Moments m = moments(c, mu / c.exposure_e, n);
        // Rounding to DN is exact here: a whole number of electrons is a whole number of DN.
        EXPECT_NEAR(m.mean, mu, 5 * std::sqrt(mu / n)) << mu;
        EXPECT_NEAR(m.variance, mu, 5 * std::sqrt((mu + 2 * mu * mu) / n)) << mu;
    }
    // No light, no dark current: exactly zero.
    EXPECT_EQ(sensor_dn(c, 0, 7, 0), 0);
}

TEST(SensorChain, PhotonTransferCurve)
{
    // Variance against mean in DN over exposures: for g DN per electron, read noise r electrons,
    // var = g mean_above_black + g^2 r^2 + 1/12 (the rounding), until the full well clips.
    SensorChainParams c;
    c.given = true;
    c.bit_depth = 12;
    c.full_well_e = 20000;
    c.read_noise_e = 6;
    c.black_level_dn = 64;
    c.has_exposure = true;
    const double g = (4095.0 - 64) / 20000;
    const int n = 100000;
    std::vector<double> means, variances;
    for (double exposure : {200.0, 800.0, 2000.0, 5000.0, 10000.0, 15000.0}) {
        c.exposure_e = exposure;
        const Moments m = moments(c, 1.0, n);
        means.push_back(m.mean - c.black_level_dn);
        variances.push_back(m.variance);
        EXPECT_NEAR(m.mean - c.black_level_dn, g * exposure, 0.01 * g * exposure + 0.05) << exposure;
    }
    // Least-squares line through (mean, variance).
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const int k = int(means.size());
    for (int i = 0; i < k; ++i) {
        sx += means[i];
        sy += variances[i];
        sxx += means[i] * means[i];
        sxy += means[i] * variances[i];
    }
    const double slope = (k * sxy - sx * sy) / (k * sxx - sx * sx);
    EXPECT_NEAR(slope, g, 0.02 * g);
    // The curve's foot, in the dark: the read noise in DN and the rounding (the sample variance of
    // 100 000 sites is good to about 0.5 %, far better than the line's intercept).
    const Moments dark = moments(c, 0.0, n);
    EXPECT_NEAR(dark.mean, c.black_level_dn, 0.02);
    EXPECT_NEAR(dark.variance, g * g * 36 + 1.0 / 12, 0.04);
    // Past the full well: every site reads the largest DN, with no variance left.
    c.exposure_e = 40000;
    const Moments clipped = moments(c, 1.0, 1000);
    EXPECT_EQ(clipped.mean, 4095);
    EXPECT_EQ(clipped.variance, 0);
}

TEST(SensorChain, FixedPatternIsTheSensorsAndTheNoiseTheFrames)
{
    // A frame is a function of (seed, picture): rendering it again gives it again.
    SensorChainParams c = unit_gain();
    c.read_noise_e = 2;
    EXPECT_EQ(sensor_dn(c, 0.2, 5, 1), sensor_dn(c, 0.2, 5, 1));
    // DSNU alone in the dark: the same offsets for every seed (one sensor), a Gaussian of dsnu
    // electrons rms over the pixels.
    SensorChainParams d = unit_gain();
    d.dsnu_e = 40;
    d.black_level_dn = 1000;
    SensorChainParams d1 = d;
    d1.seed = 99;
    for (std::uint64_t k = 0; k < 100; ++k)
        EXPECT_EQ(sensor_dn(d, 0, k, 2), sensor_dn(d1, 0, k, 2)) << k;
    const Moments o = moments(d, 0.0, 50000);
    const double gain = (65535.0 - 1000) / 65535;  // DN per electron above the black level
    EXPECT_NEAR(o.mean, 1000, 1.0);
    // The sample rms of 50 000 draws is good to 0.3 %: 0.6 DN is 5 of those.
    EXPECT_NEAR(std::sqrt(o.variance), std::sqrt(40.0 * 40 * gain * gain + 1.0 / 12), 0.6);
    // Read noise alone in the dark: another seed, another frame.
    SensorChainParams r = unit_gain();
    r.read_noise_e = 40;
    r.black_level_dn = 1000;
    SensorChainParams r1 = r;
    r1.seed = 99;
    int differ = 0;
    for (std::uint64_t k = 0; k < 100; ++k)
        differ += sensor_dn(r, 0, k, 2) != sensor_dn(r1, 0, k, 2);
    EXPECT_GT(differ, 90);
    // PRNU: at a high exposure the gain pattern dominates; var = mu (shot) + (prnu mu)^2 (pattern).
    SensorChainParams p = unit_gain();
    p.prnu = 0.02;
    const double mu = 50000;
    const Moments m = moments(p, mu / p.exposure_e, 50000);
    EXPECT_NEAR(std::sqrt(m.variance), std::sqrt(mu + 0.02 * 0.02 * mu * mu), 0.03 * 0.02 * mu);
}

TEST(SensorChain, SeedChangesTheNoiseAndNothingElse)
{
    SensorChainParams a = unit_gain();
    a.read_noise_e = 3;
    SensorChainParams b = a;
    b.seed = 1;
    const std::vector<float> picture(64 * 48 * 3, 0.5f);
    const std::vector<std::uint16_t> ra = sensor_raw(a, picture, 64, 48), rb = sensor_raw(b, picture, 64, 48);
    EXPECT_EQ(ra, sensor_raw(a, picture, 64, 48));
    EXPECT_NE(ra, rb);
    double mean_a = 0, mean_b = 0;
    for (size_t k = 0; k < ra.size(); ++k) {
        mean_a += ra[k];
        mean_b += rb[k];
    }
    EXPECT_NEAR(mean_a / ra.size(), 50, 0.5);
    EXPECT_NEAR(mean_b / rb.size(), 50, 0.5);
}

TEST(SensorChain, MosaicHasOneValueAPixel)
{
    SensorChainParams c = unit_gain();
    c.bayer = BayerPattern::GBRG;
    std::vector<float> picture(4 * 2 * 3, 0.0f);
    for (size_t k = 0; k < picture.size(); k += 3)
        picture[k + 2] = 1.0f;  // pure blue
    const std::vector<std::uint16_t> raw = sensor_raw(c, picture, 4, 2);
    ASSERT_EQ(raw.size(), 8u);
    // gbrg: row 0 is g b g b, row 1 r g r g; only blue sites see light.
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 4; ++i)
            EXPECT_EQ(raw[size_t(j) * 4 + i] > 0, j == 0 && i % 2 == 1) << i << "," << j;
}

TEST(SensorChain, RowsReadOutBandByBandAreEachSitesOwnValue)
{
    // A band of rows read out on its own, on any number of threads, gives every site the value the
    // site's own read-out gives (sensor_dn with the pixel's index in the whole picture), with and
    // without a mosaic: the raw may be made band by band.
    SensorChainParams c = unit_gain();
    c.read_noise_e = 3;
    c.prnu = 0.01;
    const int W = 37, first = 9, rows = 7;  // rows 9 to 15 of a larger picture
    std::vector<float> band(size_t(rows) * W * 3);
    for (size_t k = 0; k < band.size(); ++k)
        band[k] = float((k * 7919) % 1000) / 1000.0f;
    for (BayerPattern pattern : {BayerPattern::None, BayerPattern::GRBG}) {
        c.bayer = pattern;
        const size_t per_pixel = pattern == BayerPattern::None ? 3 : 1;
        for (int threads : {1, 3}) {
            std::vector<std::uint16_t> raw(size_t(rows) * W * per_pixel, 0xffff);
            sensor_raw_rows(c, band.data(), W, first, rows, raw.data(), threads);
            for (int r = 0; r < rows; ++r)
                for (int i = 0; i < W; ++i) {
                    const std::uint64_t pixel = std::uint64_t(first + r) * W + i;
                    const float* rgb = &band[(size_t(r) * W + i) * 3];
                    if (pattern == BayerPattern::None) {
                        for (int ch = 0; ch < 3; ++ch)
                            ASSERT_EQ(raw[(size_t(r) * W + i) * 3 + ch], sensor_dn(c, rgb[ch], pixel, ch));
                    } else {
                        const int ch = bayer_channel(pattern, i, first + r);
                        ASSERT_EQ(raw[size_t(r) * W + i], sensor_dn(c, rgb[ch], pixel, ch)) << i << "," << r;
                    }
                }
        }
    }
}

TEST(SensorChain, RefusesWhatNoSensorHas)
{
    EXPECT_NE(check_bit_depth("bit_depth", 17), "");
    EXPECT_NE(check_bit_depth("bit_depth", 0), "");
    EXPECT_NE(check_bit_depth("bit_depth", 10.5), "");
    EXPECT_EQ(check_bit_depth("bit_depth", 10), "");
    EXPECT_NE(check_electrons("full_well", 0), "");
    EXPECT_NE(check_electrons("exposure", -5), "");
    EXPECT_NE(check_non_negative("read_noise", -1), "");
    EXPECT_NE(check_non_negative("prnu", NAN), "");
    EXPECT_NE(check_whole_number("seed", -1), "");
    EXPECT_NE(check_whole_number("seed", 2.5), "");
    EXPECT_NE(check_dn("black_level", 70000), "");
    SensorChainParams c;
    c.given = true;
    c.bit_depth = 8;
    c.black_level_dn = 255;
    EXPECT_NE(check_sensor_chain(c), "");
    c.black_level_dn = 16;
    EXPECT_EQ(check_sensor_chain(c), "");
}

} // namespace
} // namespace plenoptic
