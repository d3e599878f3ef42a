// SPDX-License-Identifier: AGPL-3.0-or-later
// Diffraction: the Airy kernel against the Airy pattern's closed forms (its
// first dark ring, and the encircled energy 1 - J0(x)^2 - J1(x)^2, Rayleigh's result), the Airy
// radius of a Lytro-class camera written out from 1.22 lambda N, and the convolution's bookkeeping.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <limits>

#include <boost/math/special_functions/bessel.hpp>
#include <gtest/gtest.h>

#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

double encircled_energy(double x)
{
    const double j0 = boost::math::cyl_bessel_j(0, x), j1 = boost::math::cyl_bessel_j(1, x);
    return 1 - j0 * j0 - j1 * j1;
}

TEST(Diffraction, PatternFarNarrowerThanAPixelStaysInItsPixel)
{
    // The centre pixel holds at least the light within the circle inscribed in it (half a pixel),
    // over the window's share; down to radii where no sample point reaches the pattern (a fuzzer
    // found 1e-16 px: the sample count overflowed an int and the weights divided by zero).
    const double x1 = 3.8317059702075125;
    for (double radius : {0.2, 0.05, 0.01, 0.004, 1e-6, 1e-16}) {
        const AiryKernel k = airy_kernel(radius, radius);
        EXPECT_EQ(k.kx, 1);
        double total = 0;
        for (double w : k.weights) {
            ASSERT_TRUE(std::isfinite(w)) << radius;
            total += w;
        }
        EXPECT_NEAR(total, 1, 1e-12) << radius;
        const double inscribed = std::min(1.0, encircled_energy(0.5 / radius * x1) /
                                                   encircled_energy(kAiryKernelRadii * x1));
        EXPECT_GE(k.at(0, 0), inscribed - 0.01) << radius;
    }
}

TEST(Diffraction, AiryPatternIsDarkAtItsRadiusAndOneAtTheCentre)
{
    EXPECT_EQ(airy_intensity(0, 2.5), 1);
    EXPECT_LT(airy_intensity(2.5, 2.5), 1e-12);
    // Half maximum at 0.5145 lambda N from the centre (the FWHM is 1.029 lambda N), 1.22 lambda N being the radius.
    EXPECT_NEAR(airy_intensity(2.5 * 0.5145 / 1.22, 2.5), 0.5, 2e-3);
}

TEST(Diffraction, KernelHoldsTheEncircledEnergyOfThePattern)
{
    // An Airy radius of 6 pixels: the pixels whose centres lie within r of the centre hold the
    // encircled energy at r, over the energy within the window (4 radii; 95.9 %).
    const double radius = 6;
    const AiryKernel k = airy_kernel(radius, radius);
    EXPECT_EQ(k.kx, 24);
    EXPECT_EQ(k.ky, 24);
    double total = 0;
    for (double w : k.weights)
        total += w;
    EXPECT_NEAR(total, 1, 1e-12);
    const double x1 = 3.8317059702075125;
    const double window = encircled_energy(kAiryKernelRadii * x1);
    EXPECT_NEAR(window, 0.959, 0.002);
    for (double r : {1.0, 1.5, 2.0, 3.0}) {
        double inside = 0;
        for (int dy = -k.ky; dy <= k.ky; ++dy)
            for (int dx = -k.kx; dx <= k.kx; ++dx)
                if (std::hypot(dx, dy) <= r * radius)
                    inside += k.at(dx, dy);
        // Pixels straddle the circle: a ring of about 2 pi r pixels half in, half out.
        EXPECT_NEAR(inside, encircled_energy(r * x1) / window, 0.012) << "within " << r << " Airy radii";
    }
    EXPECT_NEAR(encircled_energy(x1), 0.838, 1e-3);  // Rayleigh's 83.8 % inside the first dark ring
    // Symmetric: the pattern is round.
    EXPECT_DOUBLE_EQ(k.at(3, -5), k.at(-5, 3));
    EXPECT_DOUBLE_EQ(k.at(3, -5), k.at(-3, 5));
}

TEST(Diffraction, LytroClassMicrolensesSpreadLightByAboutAPixel)
{
    // 14 um pitch f/2 microlenses focused at d = f = 28 um on 1.4 um pixels: 1.22 * 0.55 um * 2 =
    // 1.342 um, 0.96 pixels, in green.
    CameraParams p = test::plenoptic_camera(GridType::Hexagonal, 0.014, 0.028, 0.028, 6.45, 2, 6.5);
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.0014;
    p.diffraction.given = true;
    ASSERT_EQ(check_diffraction(p.diffraction, p), "");
    const PlenopticCamera m = make_camera(p);
    const Diffraction d = diffraction_of(m, p.diffraction);
    ASSERT_TRUE(d.applied);
    EXPECT_STREQ(d.aperture, "microlens");
    EXPECT_NEAR(d.airy_radius_mm[1], 1.22 * 550e-6 * 2, 1e-12);
    EXPECT_NEAR(d.airy_radius_mm[0] / d.airy_radius_mm[2], 610.0 / 465.0, 1e-12);
    // The main lens's pattern in the array's plane, not applied: 1.22 lambda D / A.
    EXPECT_NEAR(d.main_lens_airy_radius_at_array_mm[1], 1.22 * 550e-6 * 6.5 / (6.45 / 2), 1e-12);
}

TEST(Diffraction, WithoutAnArrayTheExitPupilDiffracts)
{
    CameraParams p = test::thin_lens_camera(50, 8, 52);
    p.diffraction.given = true;
    p.diffraction.wavelengths_nm[1] = 500;
    const Diffraction d = diffraction_of(make_camera(p), p.diffraction);
    EXPECT_STREQ(d.aperture, "main_lens");
    EXPECT_NEAR(d.airy_radius_mm[1], 1.22 * 500e-6 * 52 / (50.0 / 8), 1e-12);
}

TEST(Diffraction, RefusedWhereAnApertureHasNoSize)
{
    CameraParams p = test::plenoptic_camera(GridType::Hexagonal, 0.1, 0, 0.4, 16, 4, 16.5);
    p.diffraction.given = true;
    EXPECT_NE(check_diffraction(p.diffraction, p).find("pinhole microlenses"), std::string::npos);
    CameraParams q;
    q.main.given = true;
    q.main.type = MainLensType::Pinhole;
    q.diffraction.given = true;
    EXPECT_NE(check_diffraction(q.diffraction, q).find("pinhole main lens"), std::string::npos);
    EXPECT_NE(check_wavelength(50).find("from 100 to 20000"), std::string::npos);
    EXPECT_NE(check_wavelength(NAN).find("finite"), std::string::npos);
    EXPECT_EQ(check_wavelength(550), "");
}

TEST(Diffraction, RefusesAnAiryPatternWiderThanSixteenPixels)
{
    // 50 mm f/8 without an array: 1.22 * 0.61 um * 8.3 = 6.2 um, red; on 0.5 um pixels 12 pixels,
    // on 0.3 um pixels 21 pixels.
    CameraParams p = test::thin_lens_camera(50, 8, 52);
    p.diffraction.given = true;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.0005;
    EXPECT_EQ(check_diffraction_size(make_camera(p), p.diffraction), "");
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.0003;
    const std::string message = check_diffraction_size(make_camera(p), p.diffraction);
    EXPECT_NE(message.find("Airy radius of 20.6"), std::string::npos) << message;
    EXPECT_NE(message.find("more than 16"), std::string::npos) << message;
    p.diffraction.given = false;
    EXPECT_EQ(check_diffraction_size(make_camera(p), p.diffraction), "");
}

TEST(Diffraction, ConvolutionSpreadsAPointIntoTheKernelAndKeepsAFlatField)
{
    const int W = 41, H = 31;
    AiryKernel kernels[3] = {airy_kernel(2.2, 2.2), airy_kernel(2.0, 1.5), airy_kernel(1.6, 1.6)};
    std::vector<float> picture(size_t(W) * H * 3, 0.0f);
    for (int c = 0; c < 3; ++c)
        picture[(size_t(15) * W + 20) * 3 + c] = 1.0f;
    std::vector<float> two = picture;
    ASSERT_TRUE(convolve_channels(picture, W, H, 3, kernels, nullptr, 1));
    ASSERT_TRUE(convolve_channels(two, W, H, 3, kernels, nullptr, 2));
    EXPECT_EQ(picture, two);  // the same bytes with one or two threads
    for (int c = 0; c < 3; ++c) {
        double total = 0;
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i)
                total += picture[(size_t(j) * W + i) * 3 + c];
        EXPECT_NEAR(total, 1, 1e-6);  // light is kept
        EXPECT_NEAR(picture[(size_t(15 + 2) * W + 20 - 1) * 3 + c], kernels[c].at(-1, 2), 1e-7);
    }
    // A flat field stays flat away from the edges (outside counts as black).
    std::vector<float> flat(size_t(W) * H * 3, 0.5f);
    ASSERT_TRUE(convolve_channels(flat, W, H, 3, kernels, nullptr, 2));
    EXPECT_NEAR(flat[(size_t(15) * W + 20) * 3 + 1], 0.5, 1e-6);
    EXPECT_LT(flat[0], 0.45);
    // Cancelled: says so.
    std::vector<float> again(size_t(W) * H * 3, 0.25f);
    EXPECT_FALSE(convolve_channels(again, W, H, 3, kernels, [] { return true; }, 2));
}

// The convolution's definition, summed directly in double precision: the answer the transforms
// must give within float rounding.
std::vector<float> direct_convolution(const std::vector<float>& picture, int W, int H, int channels, const AiryKernel* kernels)
{
    std::vector<float> out(picture.size());
    for (int c = 0; c < channels; ++c)
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const AiryKernel& k = kernels[c];
                double sum = 0;
                for (int dy = -k.ky; dy <= k.ky; ++dy)
                    for (int dx = -k.kx; dx <= k.kx; ++dx) {
                        const int x = i - dx, y = j + dy;
                        if (x >= 0 && x < W && y >= 0 && y < H)
                            sum += k.at(dx, dy) * picture[(size_t(y) * W + x) * channels + c];
                    }
                out[(size_t(j) * W + i) * channels + c] = float(sum);
            }
    return out;
}

// A picture of microimage-like discs of light over black, with a few bright specks: values over
// five decades and large black areas, as a raw behind an array has them.
std::vector<float> test_picture(int W, int H, int channels)
{
    std::vector<float> picture(size_t(W) * H * channels, 0.0f);
    std::uint64_t state = 12345;
    auto uniform = [&state]() {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return double(state >> 11) / 9007199254740992.0;
    };
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const double u = std::fmod(i, 14.0) - 7, v = std::fmod(j, 12.0) - 6;
            for (int c = 0; c < channels; ++c)
                if (u * u + v * v < 30)
                    picture[(size_t(j) * W + i) * channels + c] = float((0.2 + 0.8 * uniform()) * (c + 1) / 3);
        }
    for (int n = 0; n < 40; ++n)
        picture[(size_t(uniform() * H) * W + size_t(uniform() * W)) * channels] = float(1e5 * uniform());
    return picture;
}

// |a - b| within float rounding of the light around the pixel: a few units in the last place of
// the largest source value the kernel's window reaches (the sum's terms are as large as that).
void expect_within_float_rounding(const std::vector<float>& got, const std::vector<float>& want, const std::vector<float>& picture,
                                  int W, int H, int channels, const AiryKernel* kernels)
{
    int worse = 0;
    for (int c = 0; c < channels; ++c)
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                float largest = 0;
                const AiryKernel& k = kernels[c];
                for (int y = std::max(0, j - k.ky); y <= std::min(H - 1, j + k.ky); ++y)
                    for (int x = std::max(0, i - k.kx); x <= std::min(W - 1, i + k.kx); ++x)
                        largest = std::max(largest, picture[(size_t(y) * W + x) * channels + c]);
                const size_t at = (size_t(j) * W + i) * channels + c;
                const double tolerance = 4 * std::numeric_limits<float>::epsilon() * std::max(double(largest), double(want[at]));
                if (!(std::fabs(double(got[at]) - want[at]) <= tolerance) && worse++ < 5)
                    ADD_FAILURE() << "pixel " << i << ", " << j << " channel " << c << ": " << got[at] << " against the direct sum's "
                                  << want[at] << " (tolerance " << tolerance << ")";
                EXPECT_GE(got[at], 0.0f);
            }
    EXPECT_EQ(worse, 0);
}

TEST(Diffraction, ConvolutionByTilesEqualsTheDirectSumWithinFloatRounding)
{
    // Larger than one tile both ways (several tiles in a band, several bands), kernels of
    // different sizes per channel, odd sizes.
    const int W = kConvolutionTile + 151, H = kConvolutionTile + 97;
    const AiryKernel kernels[3] = {airy_kernel(2.2, 2.2), airy_kernel(1.4, 0.9), airy_kernel(0.6, 0.6)};
    const std::vector<float> picture = test_picture(W, H, 3);
    const std::vector<float> want = direct_convolution(picture, W, H, 3, kernels);
    std::vector<float> one = picture, two = picture;
    ASSERT_TRUE(convolve_channels(one, W, H, 3, kernels, nullptr, 1));
    ASSERT_TRUE(convolve_channels(two, W, H, 3, kernels, nullptr, 2));
    EXPECT_EQ(one, two);  // the same bytes with one or two threads
    expect_within_float_rounding(one, want, picture, W, H, 3, kernels);
    size_t equal = 0;
    for (size_t n = 0; n < want.size(); ++n)
        equal += one[n] == want[n];
    std::printf("convolution by tiles: %zu of %zu values equal to the direct sum's float\n", equal, want.size());
}

TEST(Diffraction, ConvolutionByRowsReadsEachRowOnceAndWritesOnlyWhatItHasRead)
{
    // The picture streamed through the callbacks, never held by the convolution: each source row
    // read once from the top down, each output row written once from the top down and only after
    // every row its kernel reaches has been read (so it may be written in place), and the result
    // the direct sum's within float rounding, in a separate buffer.
    const int W = kConvolutionTile + 31, H = 2 * kConvolutionTile + 75, channels = 3;
    const AiryKernel kernels[3] = {airy_kernel(2.2, 2.2), airy_kernel(1.4, 0.9), airy_kernel(0.6, 0.6)};
    const int KY = kernels[0].ky;
    const std::vector<float> picture = test_picture(W, H, channels);
    const std::vector<float> want = direct_convolution(picture, W, H, channels, kernels);
    const size_t row = size_t(W) * channels;
    std::vector<float> got(picture.size(), -1.0f);
    int next_read = 0, next_write = 0, reads = 0, writes = 0;
    const RowReader read = [&](int first, int count, float* to) {
        EXPECT_EQ(first, next_read);
        EXPECT_GT(count, 0);
        EXPECT_LE(first + count, H);
        next_read = first + count;
        ++reads;
        std::copy(picture.begin() + ptrdiff_t(first * row), picture.begin() + ptrdiff_t((first + count) * row), to);
        return true;
    };
    const RowWriter write = [&](int first, int count, const float* from) {
        EXPECT_EQ(first, next_write);
        EXPECT_GE(next_read, std::min(H, first + count + KY)) << "rows " << first << " + " << count << " written before read";
        next_write = first + count;
        ++writes;
        std::copy(from, from + size_t(count) * row, got.begin() + ptrdiff_t(first * row));
        return true;
    };
    ASSERT_TRUE(convolve_rows(W, H, channels, kernels, read, write, nullptr, 2));
    EXPECT_EQ(next_read, H);
    EXPECT_EQ(next_write, H);
    EXPECT_GE(writes, 3);  // several bands
    // Against the direct sum: within float rounding of the values (the transforms also leave
    // noise of order 1e-17 where the direct sum is exactly 0 beside a 1e5 spot of the tile).
    double largest = 0, worst = 0;
    for (size_t n = 0; n < want.size(); ++n) {
        largest = std::max(largest, double(picture[n]));
        worst = std::max(worst, std::fabs(double(got[n]) - want[n]) / std::max(1.0, double(want[n])));
    }
    EXPECT_LT(worst, 8 * std::numeric_limits<float>::epsilon()) << "largest value " << largest;
    std::vector<float> in_place = picture;
    ASSERT_TRUE(convolve_channels(in_place, W, H, channels, kernels, nullptr, 1));
    EXPECT_EQ(in_place, got);

    // A reader or a writer that stops the convolution stops it.
    int calls = 0;
    const RowWriter refuse = [&](int, int, const float*) { return ++calls > 1 ? false : true; };
    next_read = 0;
    EXPECT_FALSE(convolve_rows(W, H, channels, kernels, read, refuse, nullptr, 2));
    EXPECT_EQ(calls, 2);
    const RowReader fail = [&](int, int, float*) { return false; };
    EXPECT_FALSE(convolve_rows(W, H, channels, kernels, fail, write, nullptr, 2));
    std::printf("convolution by rows: %d reads, %d writes of bands\n", reads, writes);
}

TEST(Diffraction, ConvolutionWithTheWidestKernelAcceptedEqualsTheDirectSum)
{
    // An Airy radius of 16 pixels (kMaxAiryRadiusPx): a 129 x 129 kernel, wider than the picture.
    const int W = 101, H = 77, channels = 1;
    const AiryKernel kernel = airy_kernel(kMaxAiryRadiusPx, kMaxAiryRadiusPx * 0.75);
    const std::vector<float> picture = test_picture(W, H, channels);
    const std::vector<float> want = direct_convolution(picture, W, H, channels, &kernel);
    std::vector<float> got = picture;
    ASSERT_TRUE(convolve_channels(got, W, H, channels, &kernel, nullptr, 2));
    expect_within_float_rounding(got, want, picture, W, H, channels, &kernel);
}

} // namespace
} // namespace plenoptic
