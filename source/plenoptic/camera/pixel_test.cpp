// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the pixel loop: blocked samples, adaptive stop, determinism, overlap weighting.

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/camera/pixel.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;

// A scene whose radiance depends on the ray: enough structure to tell samples apart.
Rgbt textured(const OpticsRay& ray)
{
    const double a = std::sin(40 * ray.dir.x) * std::cos(30 * ray.dir.y);
    return Rgbt{0.5 + 0.5 * a, 0.25 + 0.1 * ray.origin_mm.x, 0.5 - 0.5 * a, 0.0};
}

// Plenoptic 1.0 with f-number-matched hexagonal microlenses (f/4), 20 um pixels: tools/bench's
// camera. Its 8-pixel microimages put many pixels at a rim, partly lit.
CameraParams matched_plenoptic1()
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.16, 0.64, 0.64, 16, 4, 16.1);
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.02;
    return p;
}

TEST(Pixel, BlockedSamplesAreBlackAndOpaqueNeverBackground)
{
    // Pinhole array behind a small main aperture: small microimage discs, dark cells between.
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 0.5, 0, 2, 50, 50, 52);
    params.sampling.samples = 16;
    const PlenopticCamera m = make_camera(params);
    const int W = 101, H = 101;
    int calls = 0;
    // The scene returns fully transparent background for every ray it is asked about.
    auto background = [&](const OpticsRay&) {
        ++calls;
        return Rgbt{1, 1, 1, 1};
    };
    const Rgbt dark = shade_pixel(with_film(m, W, H), 70, 50, background);
    EXPECT_EQ(calls, 0) << "no ray reaches a pixel between the microimages";
    EXPECT_EQ(dark.r, 0.0);
    EXPECT_EQ(dark.g, 0.0);
    EXPECT_EQ(dark.b, 0.0);
    EXPECT_EQ(dark.t, 0.0) << "a pixel no ray reaches is opaque, never background";

    const Rgbt lit = shade_pixel(with_film(m, W, H), 50, 50, background);
    EXPECT_EQ(calls, 16);
    EXPECT_EQ(lit.r, 1.0);
    EXPECT_EQ(lit.t, 1.0);

    // At the disc's edge some samples are blocked: the value is the unblocked fraction of the
    // 4 x 16 sample points looked at (the vignetting probes).
    bool partial = false;
    for (int i = 51; i < 60 && !partial; ++i) {
        const Rgbt edge = shade_pixel(with_film(m, W, H), i, 50, background);
        if (edge.r > 0 && edge.r < 1) {
            partial = true;
            EXPECT_EQ(edge.r, edge.t);
            const int probes = 16 * kVignettingProbesPerSample;
            EXPECT_NEAR(edge.r * probes, std::round(edge.r * probes), 1e-9) << "a whole number of the probes";
            int first;
            EXPECT_EQ(edge.r, double(detail::passing_samples(with_film(m, W, H), i, 50, 0, probes, &first)) / probes);
        }
    }
    EXPECT_TRUE(partial) << "expected a partly vignetted pixel near the microimage's edge";
}

TEST(Pixel, AdaptiveSamplingStopsEarlyOnFlatScenesAndGoesOnOnNoisyOnes)
{
    CameraParams params = test::thin_lens_camera(50, 2, 55);
    params.sampling.adaptive = true;
    params.sampling.samples_min = 8;
    params.sampling.samples_max = 64;
    const PlenopticCamera m = with_film(make_camera(params), 64, 64);
    int calls = 0;
    auto flat = [&](const OpticsRay&) {
        ++calls;
        return Rgbt{0.3, 0.3, 0.3, 0};
    };
    const Rgbt value = shade_pixel(m, 10, 10, flat);
    EXPECT_EQ(calls, 8) << "zero variance after the minimum";
    EXPECT_NEAR(value.r, 0.3, 1e-15);

    calls = 0;
    auto noisy = [&](const OpticsRay& ray) {
        ++calls;
        return Rgbt{ray.origin_mm.x > 0 ? 1.0 : 0.0, 0, 0, 0};
    };
    shade_pixel(m, 10, 10, noisy);
    EXPECT_GT(calls, 8);
    EXPECT_LE(calls, 64);
    EXPECT_EQ((calls - 8) % 4 == 0 || calls == 64, true) << calls << " samples: batches of 4 after the minimum";
}

TEST(Pixel, AdaptiveSamplingDoesNotTakeAnUnluckyBlockedStartForADarkPixel)
{
    // Plenoptic 1.0 with f-number-matched microlenses: pixels at a microimage's rim are partly
    // lit, and with uniform samples, for some of them every one of the first samples is blocked.
    // Aimed samples (camera/aim.h) behind this thin main lens are aimed exactly: none of a lit
    // pixel's samples is blocked, so no start is unlucky.
    const int W = 160, H = 120, minimum = 16, maximum = 256;
    for (const bool aim : {false, true}) {
        CameraParams fixed = matched_plenoptic1();
        CameraParams adaptive = fixed;
        fixed.sampling.samples = maximum;
        adaptive.sampling.adaptive = true;
        adaptive.sampling.samples_min = minimum;
        adaptive.sampling.samples_max = maximum;
        PlenopticCamera m_fixed = with_film(make_camera(fixed), W, H), m_adaptive = with_film(make_camera(adaptive), W, H);
        ASSERT_TRUE(m_fixed.sampling.aim && m_adaptive.sampling.aim);
        m_fixed.sampling.aim = m_adaptive.sampling.aim = aim;
        auto white = [](const OpticsRay&) { return Rgbt{1, 1, 1, 0}; };
        int unlucky = 0, lit_pixels = 0;
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                bool first_lit = false;
                for (int n = 0; n < minimum && !first_lit; ++n) {
                    OpticsRay ray;
                    first_lit = (ray = m_adaptive.generate_ray(i, j, make_sample(i, j, n, maximum))).passed;
                }
                const bool lit = shade_pixel(m_fixed, i, j, white).r > 0;
                const Rgbt value = shade_pixel(m_adaptive, i, j, white);
                EXPECT_EQ(value.r > 0, lit) << "pixel " << i << "," << j << ": dark exactly when no sample passes";
                EXPECT_EQ(m_adaptive.receives_light(i, j), lit) << "pixel " << i << "," << j;
                lit_pixels += lit;
                if (lit && !first_lit)
                    ++unlucky;
            }
        EXPECT_GT(lit_pixels, W * H / 2);
        if (aim) {
            EXPECT_EQ(unlucky, 0) << "aimed exactly, a lit pixel's first samples pass";
        } else {
            EXPECT_GT(unlucky, 0) << "the set-up should have rim pixels whose first samples are all blocked";
        }
    }
}

TEST(Pixel, VignettingProbesBringRimPixelsCloserToTheirTrueLitFraction)
{
    // White scene: a pixel's exact value is the fraction of its (pixel x aperture) domain that
    // passes the apertures. Compare 16 samples with and without the probes against 4096 points.
    const int W = 160, H = 120, samples = 16, reference = 4096;
    CameraParams params = matched_plenoptic1();
    params.sampling.samples = samples;
    const PlenopticCamera m = with_film(make_camera(params), W, H);
    // The truth and the plain count from uniform samples (the camera aims its own: camera/aim.h).
    PlenopticCamera uniform = m;
    uniform.sampling.aim = false;
    auto white = [](const OpticsRay&) { return Rgbt{1, 1, 1, 0}; };
    double error_plain = 0, error_probed = 0;
    int rim = 0;
    for (int j = 0; j < H; j += 2)
        for (int i = 0; i < W; i += 2) {
            int first;
            const double truth = double(detail::passing_samples(uniform, i, j, 0, reference, &first)) / reference;
            if (truth == 0 || truth == 1)
                continue;
            ++rim;
            const double plain = double(detail::passing_samples(uniform, i, j, 0, samples, &first)) / samples;
            error_plain += (plain - truth) * (plain - truth);
            const double probed = shade_pixel(m, i, j, white).r;
            error_probed += (probed - truth) * (probed - truth);
        }
    ASSERT_GT(rim, 500) << "f-number-matched microimages: many pixels at their rims";
    EXPECT_LT(error_probed, 0.5 * error_plain) << "squared error: " << error_probed << " vs " << error_plain;
}

TEST(Pixel, DeterministicWhateverThePixelOrder)
{
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 0.2, 1.5, 2, 50, 4, 55);
    params.sampling.samples = 8;
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
    const PlenopticCamera m = make_camera(params);
    const int W = 40, H = 30;
    std::vector<Rgbt> forward, backward(W * H);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            forward.push_back(shade_pixel(with_film(m, W, H), i, j, textured));
    for (int j = H - 1; j >= 0; --j)
        for (int i = W - 1; i >= 0; --i)
            backward[j * W + i] = shade_pixel(with_film(m, W, H), i, j, textured);
    for (int k = 0; k < W * H; ++k) {
        ASSERT_EQ(forward[k].r, backward[k].r) << k;
        ASSERT_EQ(forward[k].g, backward[k].g) << k;
        ASSERT_EQ(forward[k].b, backward[k].b) << k;
    }
}

TEST(Pixel, OverlapModellingLeavesSingleLensPixelsUnchanged)
{
    // Microimages cannot overlap here (main lens at twice the matched f-number); force the
    // overlap path anyway: a pixel that only its own lens reaches must keep its value exactly.
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 10, 50);
    params.sampling.samples = 16;
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.005;
    const PlenopticCamera plain = make_camera(params);
    ASSERT_FALSE(plain.overlap.modelled);
    PlenopticCamera forced = plain;
    forced.overlap.modelled = true;
    forced.overlap.rings = 2;
    const int W = 100, H = 100;
    int single = 0;
    LensIndex lenses[kMaxOverlapLenses];
    for (int j = 0; j < H; ++j) {
        for (int i = 0; i < W; ++i) {
            if (overlap_lenses(with_film(forced, W, H), i, j, lenses, kMaxOverlapLenses) != 1)
                continue;
            ++single;
            const Rgbt a = shade_pixel(with_film(plain, W, H), i, j, textured);
            const Rgbt b = shade_pixel(with_film(forced, W, H), i, j, textured);
            ASSERT_EQ(a.r, b.r) << i << "," << j;
            ASSERT_EQ(a.g, b.g) << i << "," << j;
            ASSERT_EQ(a.b, b.b) << i << "," << j;
            ASSERT_EQ(a.t, b.t) << i << "," << j;
        }
    }
    EXPECT_GT(single, W * H / 2) << "most pixels are reached by their own lens only";
}

TEST(Pixel, OverlapLensesEachGetAWholeSamplePattern)
{
    // Each of a pixel's L lenses gets the pixel and the aperture evenly: its 32 samples have their
    // mean near the centre (0.5) in all four coordinates and fill every quarter of each. Measured
    // over 200 pixels: mean within 0.061 of 0.5, quarters 8 +- 3. Every L-th point of the pixel's
    // one Halton sequence, as before, did not: for L = 2 the even points have the aperture's u (base
    // 2) in one half of [0, 1); for L = 2 .. 7, means up to 0.44 from the centre, quarters 8 +- 24.
    for (int lenses = 1; lenses <= 7; ++lenses) {
        for (int pixel = 0; pixel < 16; ++pixel) {
            const int count = 32 * lenses;
            double sum[kMaxOverlapLenses][4] = {};
            int quarter[kMaxOverlapLenses][4][4] = {};
            int share[kMaxOverlapLenses] = {};
            for (int n = 0; n < count; ++n) {
                int slot = -1;
                const CameraSample s = detail::lens_sample(3 * pixel, 100 - pixel, n, count, lenses, &slot);
                // Each round of L samples: the own lens (slot 0) first, then every other lens once
                // (in the first round in a rotated order, then in order).
                ASSERT_EQ(slot == 0, n % lenses == 0);
                ASSERT_EQ(share[slot], n / lenses);
                if (n >= lenses)
                    ASSERT_EQ(slot, n % lenses);
                const double v[4] = {s.pixel_u, s.pixel_v, s.lens_u, s.lens_v};
                for (int d = 0; d < 4; ++d) {
                    sum[slot][d] += v[d];
                    ++quarter[slot][d][int(v[d] * 4)];
                }
                ++share[slot];
            }
            for (int slot = 0; slot < lenses; ++slot) {
                ASSERT_EQ(share[slot], 32);
                for (int d = 0; d < 4; ++d) {
                    EXPECT_NEAR(sum[slot][d] / 32, 0.5, 0.08)
                        << "L " << lenses << " pixel " << pixel << " lens " << slot << " dimension " << d;
                    for (int q = 0; q < 4; ++q)
                        EXPECT_NEAR(quarter[slot][d][q], 8, 4)
                            << "L " << lenses << " pixel " << pixel << " lens " << slot << " dimension " << d;
                }
            }
        }
    }
    // One lens: exactly the plain samples, so pixels only their own lens reaches keep their value.
    for (int n = 0; n < 16; ++n) {
        int slot = -1;
        const CameraSample a = detail::lens_sample(5, 6, n, 16, 1, &slot);
        const CameraSample b = make_sample(5, 6, n, 16);
        EXPECT_EQ(slot, 0);
        EXPECT_EQ(a.pixel_u, b.pixel_u);
        EXPECT_EQ(a.pixel_v, b.pixel_v);
        EXPECT_EQ(a.lens_u, b.lens_u);
        EXPECT_EQ(a.lens_v, b.lens_v);
    }
}

TEST(Pixel, FewerSamplesThanLensesStillEstimateTheSumOverLenses)
{
    // A pixel with L lenses takes m < L samples: the sum over its lenses of each lens's light, here a
    // constant a lens (any sample through lens s sees v[s]), must come out right on average over
    // pixels: the own lens's always, the others' as a random choice scaled by (L - 1) / (m - 1).
    // The sum is known (independent of the code); the old rule (samples to lenses 0 .. m-1 in
    // order, the sum scaled by L / m) gave L / m times the first m lenses' light: 2.7 times the
    // truth here for m = 3 of L = 7. Also: every lens is used, and one sample gives the own lens.
    const int L = 7;
    const double v[L] = {0.5, 0.0, 0.3, 0.0, 0.1, 0.05, 0.2};
    const double truth = 0.5 + 0.0 + 0.3 + 0.0 + 0.1 + 0.05 + 0.2;
    for (int m = 1; m <= 2 * L + 1; ++m) {
        double total = 0;
        int pixels = 0;
        int used[L] = {};
        for (int j = 0; j < 60; ++j) {
            for (int i = 0; i < 60; ++i) {
                detail::SampleSums<1> sums[L];
                for (int s = 0; s < L; ++s) {
                    sums[s].sum[0] = sums[s].sum_sq[0] = 0;
                    sums[s].count = 0;
                }
                for (int n = 0; n < m; ++n) {
                    int slot = -1;
                    detail::lens_sample(i, j, n, m, L, &slot);
                    ASSERT_GE(slot, 0);
                    ASSERT_LT(slot, L);
                    ++used[slot];
                    detail::Channels<1> c;
                    c.v[0] = v[slot];
                    detail::add_sample<1>(&sums[slot], c);
                }
                double value[1], variance[1];
                detail::estimate<1>(sums, L, value, variance);
                total += value[0];
                ++pixels;
            }
        }
        const double mean = total / pixels;
        if (m == 1) {
            EXPECT_DOUBLE_EQ(mean, v[0]);  // the 1-sample pixel: its own lens
            continue;
        }
        // The others' part is a random choice of m - 1 of 6 lenses a pixel: over 3600 pixels its
        // mean is within 2 % of theirs (m >= L: every lens sampled, exact).
        EXPECT_NEAR(mean, truth, m >= L ? 1e-12 : 0.02 * truth) << m << " samples of " << L << " lenses";
        for (int s = 1; s < L; ++s)
            EXPECT_GT(used[s], 0) << "lens slot " << s << " never sampled with " << m << " samples";
    }
}

TEST(Pixel, OverlapPixelsAreUnbiasedEstimatesOfEachLensIntegral)
{
    // Microimages overlap (f/2.5 over f/10-matched microlenses). For pixels that two or more lenses
    // reach, shade a scene linear in the ray (its point on the main lens and its direction): the
    // value must be the sum over lenses of the integral over pixel x aperture (blocked rays
    // black), here a 12^4-point midpoint rule through each lens with generate_ray_unaimed (the
    // rendered samples are aimed where light passes, camera/aim.h, and weighted for it). Measured with
    // 1024 samples over these 100 pixels (3 to 5 lenses each): worst error 0.023, rms 0.0056 (64
    // samples: 0.15, 256: 0.057: it converges). With sample n through lens n mod L of one Halton
    // sequence, as before, it did not: worst 0.32, rms 0.037 at 1024 samples, as at 256 - the bias
    // that moved the rendered blobs of tests/ground_truth/test_projection_regimes.py by 1.3 px.
    const double p = 0.1, d = 0.5, F = 50, D = 50;
    const double cell = p * (1 + d / D);
    CameraParams params = plenoptic_camera(GridType::Rectangular, p, d, d, F, 2.5, D);
    params.sampling.samples = 1024;
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = cell / 5;
    const PlenopticCamera m = make_camera(params);
    ASSERT_TRUE(m.overlap.modelled);
    const int W = 30, H = 30;
    const double A = F / 2.5;
    auto scene = [A](const OpticsRay& ray) {
        return Rgbt{ray.origin_mm.x / A + 0.5, ray.origin_mm.y / A + 0.5, 10 * ray.dir.x + 0.5, 0.0};
    };
    const int grid = 12;
    int compared = 0;
    for (int j = 10; j < 20; ++j) {
        for (int i = 10; i < 20; ++i) {
            LensIndex lenses[kMaxOverlapLenses];
            const int L = overlap_lenses(with_film(m, W, H), i, j, lenses, kMaxOverlapLenses);
            if (L < 2)
                continue;
            double truth[3] = {0, 0, 0};
            for (int s = 0; s < L; ++s) {
                double sum[3] = {0, 0, 0};
                for (int a = 0; a < grid; ++a)
                    for (int b = 0; b < grid; ++b)
                        for (int c = 0; c < grid; ++c)
                            for (int e = 0; e < grid; ++e) {
                                const CameraSample sample{(a + 0.5) / grid, (b + 0.5) / grid, (c + 0.5) / grid,
                                                          (e + 0.5) / grid};
                                OpticsRay ray;
                                if (!(ray = generate_ray_unaimed(with_film(m, W, H), i, j, sample, &lenses[s])).passed)
                                    continue;
                                const Rgbt v = scene(ray);
                                sum[0] += v.r;
                                sum[1] += v.g;
                                sum[2] += v.b;
                            }
                for (int ch = 0; ch < 3; ++ch)
                    truth[ch] += sum[ch] / (grid * grid * grid * grid);
            }
            const Rgbt got = shade_pixel(with_film(m, W, H), i, j, scene);
            const double error[3] = {got.r - truth[0], got.g - truth[1], got.b - truth[2]};
            for (int ch = 0; ch < 3; ++ch) {
                EXPECT_NEAR(error[ch], 0.0, 0.05) << "pixel " << i << "," << j << " lenses " << L << " channel " << ch;
            }
            ++compared;
        }
    }
    EXPECT_GT(compared, 10);
}

double mean_white_image(const PlenopticCamera& m)
{
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    double sum = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            sum += shade_pixel(with_film(m, W, H), i, j, [](const OpticsRay&) { return Rgbt{1, 1, 1, 0}; }).r;
    return sum / (double(W) * H);
}

TEST(Pixel, WhiteSceneMeanIsApertureImageAreaOverCellArea)
{
    // Light through a lens from the whole aperture lands on a disc of radius (A/2) d/D around every
    // cell point; summed over lenses, a white scene's mean pixel value over whole microimage cells is
    // pi (A d / 2D)^2 / (p (1 + d/D))^2, overlap or not. The image covers 11 x 11 whole cells.
    const double p = 0.1, d = 0.5, F = 50, D = 50;
    const double cell = p * (1 + d / D);
    for (double f_number : {10.0, 5.0, 2.5}) {
        CameraParams params = plenoptic_camera(GridType::Rectangular, p, d, d, F, f_number, D);
        params.sampling.samples = 16;
        params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = cell / 20;
        const PlenopticCamera m = make_camera(params);
        const int W = 220, H = 220;
        const double A = F / f_number;
        const double expected = kPi * (A * d / (2 * D)) * (A * d / (2 * D)) / (cell * cell);
        const double mean = mean_white_image(with_film(m, W, H));
        EXPECT_NEAR(mean, expected, 0.003 * expected)
            << "f/" << f_number << " overlap modelled: " << m.overlap.modelled << " rings " << m.overlap.rings;
        if (f_number == 2.5) {
            // Without overlap modelling the neighbours' light would be lost.
            PlenopticCamera without = m;
            without.overlap.modelled = false;
            EXPECT_LT(mean_white_image(with_film(without, W, H)), 0.5 * expected);
        }
    }
}

TEST(Pixel, ReceivesLightExactlyWhenSomeSampleIsTraced)
{
    // f/8 behind f/4-matched microlenses: a ring of every microimage is dark.
    CameraParams p = test::plenoptic_camera(GridType::Hexagonal, 0.2, 0.8, 0.8, 50, 8, 52);
    p.sampling.samples = 8;
    const PlenopticCamera m = make_camera(p);
    const int W = 60, H = 40;
    int dark = 0, lit = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            int traced = 0;
            shade_pixel(with_film(m, W, H), i, j, [&traced](const OpticsRay&) {
                ++traced;
                return Rgbt{1, 1, 1, 0};
            });
            EXPECT_EQ(pixel_receives_light(with_film(m, W, H), i, j), traced > 0) << "pixel " << i << "," << j;
            (traced > 0 ? lit : dark)++;
        }
    EXPECT_GT(dark, 100) << "the set-up should leave pixels in the dark";
    EXPECT_GT(lit, 100);
}

} // namespace
} // namespace plenoptic
