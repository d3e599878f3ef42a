// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of spectral sampling: the sensor response and its table, the bands' weights against the
// Gaussian's closed-form integral, the camera at a wavelength against the thick-lens and
// two-term formulas written here, and the pixel's spectral estimate against its expectation.

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/camera/pixel.h"
#include "plenoptic/camera/spectral_bands.h"
#include "plenoptic/core/test_util.h"
#include "plenoptic/sensor/spectral_response.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;

// The mean of a Gaussian of peak 1 (centre mu, full width at half maximum w) over [a, b], from
// the error function.
double gaussian_mean(double mu, double w, double a, double b)
{
    const double sigma = w / (2 * std::sqrt(2 * std::log(2.0)));
    const double k = sigma * std::sqrt(M_PI / 2);
    return k * (std::erf((b - mu) / (sigma * std::sqrt(2.0))) - std::erf((a - mu) / (sigma * std::sqrt(2.0)))) / (b - a);
}

TEST(Spectral, BandsCoverTheRangeAndWeightsFollowTheGaussiansIntegral)
{
    SpectralParams params;
    params.bands = 7;
    const std::vector<SpectralBand> bands = spectral_bands(params);
    ASSERT_EQ(bands.size(), 7u);
    EXPECT_EQ(bands.front().from_nm, 380);
    EXPECT_EQ(bands.back().to_nm, 720);
    for (size_t b = 0; b + 1 < bands.size(); ++b)
        EXPECT_NEAR(bands[b].to_nm, bands[b + 1].from_nm, 1e-12);
    for (int c = 0; c < 3; ++c) {
        double total = 0, closed_total = 0;
        std::vector<double> closed;
        for (const SpectralBand& band : bands) {
            closed.push_back(gaussian_mean(kDefaultResponseCentresNm[c], kDefaultResponseWidthsNm[c], band.from_nm, band.to_nm));
            closed_total += closed.back();
            total += band.weight[c];
        }
        EXPECT_NEAR(total, 1, 1e-12) << "channel " << c << "'s weights sum to 1";
        for (size_t b = 0; b < bands.size(); ++b)
            EXPECT_NEAR(bands[b].weight[c], closed[b] / closed_total, 2e-6) << "channel " << c << ", band " << b;
    }
    // The green curve is centred on the range's middle (550 nm): its weights are symmetric.
    for (size_t b = 0; b < bands.size(); ++b)
        EXPECT_NEAR(bands[b].weight[1], bands[bands.size() - 1 - b].weight[1], 1e-9);
    EXPECT_NEAR(channel_wavelength_nm(bands, 1), 550, 1e-9);
    EXPECT_GT(channel_wavelength_nm(bands, 0), channel_wavelength_nm(bands, 1));
    EXPECT_LT(channel_wavelength_nm(bands, 2), channel_wavelength_nm(bands, 1));
}

TEST(Spectral, ResponseTableIsReadInterpolatedAndRefusedByLine)
{
    std::string error;
    int line = 0;
    const SpectralResponse table = parse_response_table(
        "# a made-up sensor\nwavelength_nm, r, g, b\n380, 0, 0, 1\n550 0 1 0.5\n720, 1, 0, 0\n", &error, &line);
    ASSERT_EQ(error, "");
    ASSERT_EQ(table.table.size(), 3u);
    EXPECT_DOUBLE_EQ(table.at(2, 465), 0.75);     // halfway from 380 to 550: (1 + 0.5) / 2
    EXPECT_DOUBLE_EQ(table.at(0, 635), 0.5);      // halfway from 550 to 720
    EXPECT_DOUBLE_EQ(table.at(1, 550), 1);
    EXPECT_EQ(table.at(1, 379), 0);
    EXPECT_EQ(check_response(table), "");
    // The mean of the green triangle over the range is 1/2.
    EXPECT_NEAR(table.mean(1, 380, 720), 0.5, 1e-6);

    struct Bad {
        const char* text;
        int line;
        const char* fragment;
    };
    const Bad bad[] = {
        {"380, 0, 0, 1\n550, 0, 1\n720, 1, 0, 0\n", 2, "4 numbers"},
        {"380, 0, 0, 1\n550, 0, x, 0\n720, 1, 0, 0\n", 2, "not a finite number"},
        {"380, 0, 0, 1\n550, 0, -1, 0\n720, 1, 0, 0\n", 2, "0 or more"},
        {"380, 0, 0, 1\n720, 1, 0, 0\n550, 0, 1, 0\n", 3, "increase"},
        {"380, 0, 0, 1\n", 0, "at least two rows"},
        {"400, 0, 0, 1\n720, 1, 1, 0\n", 0, "span"},
    };
    for (const Bad& b : bad) {
        parse_response_table(b.text, &error, &line);
        EXPECT_NE(error.find(b.fragment), std::string::npos) << b.text << " -> " << error;
        EXPECT_EQ(line, b.line) << b.text;
    }
    // A channel that responds nowhere in the range cannot be normalised.
    const SpectralResponse blind = parse_response_table("380, 1, 0, 1\n720, 1, 0, 1\n", &error, &line);
    ASSERT_EQ(error, "");
    EXPECT_NE(check_response(blind).find("g channel responds to no wavelength"), std::string::npos);
    SpectralResponse narrow;
    narrow.fwhm_nm[2] = 0.5;
    EXPECT_NE(check_response(narrow).find("response_widths"), std::string::npos);
    EXPECT_NE(check_spectral_bands(0).find("1 to 64"), std::string::npos);
    EXPECT_NE(check_spectral_bands(2.5).find("whole number"), std::string::npos);
    EXPECT_EQ(check_spectral_bands(64), "");
}

// A singlet of N-BK7-like glass (n_d 1.5168) with an Abbe number, behind a stop.
Prescription singlet(double abbe)
{
    Prescription lens;
    lens.surfaces.push_back(LensSurface{0, 2, 1, 8, true, 1});
    Glass glass;
    glass.abbe = abbe;
    lens.surfaces.push_back(LensSurface{30, 5, 1.5168, 20, false, 2, glass});
    lens.surfaces.push_back(LensSurface{-30, 0, 1, 20, false, 3});
    return lens;
}

CameraParams singlet_camera(double abbe, double micro_abbe)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.15, 0.6, 0.6, 30, 4, 40);
    p.main = MainLensParams();
    p.main.given = true;
    p.main.type = MainLensType::Prescription;
    p.main.has_prescription = true;
    p.main.prescription = singlet(abbe);
    p.main.has_distance = true;
    p.main.distance_mm = 40;
    p.array.abbe = micro_abbe;
    return p;
}

TEST(Spectral, CameraAtAWavelengthHasTheThickLensFocalLengthOfItsIndex)
{
    const PlenopticCamera d_line = make_camera(singlet_camera(30, 40));
    for (double nm : {400.0, 486.1327, 587.5618, 656.2725, 700.0}) {
        const PlenopticCamera at = at_wavelength(d_line, nm);
        // The two-term model and the thick lens in air, written here: 1/f = (n - 1) (1/R1 - 1/R2)
        // + (n - 1)^2 t / (n R1 R2).
        const double x = 523655.0 / (nm * nm) - 1.5168;
        const double n = 1.5168 + 0.5168 / 30 * x;
        const double R1 = 30, R2 = -30, t = 5;
        const double f = 1 / ((n - 1) * (1 / R1 - 1 / R2) + (n - 1) * (n - 1) * t / (n * R1 * R2));
        EXPECT_NEAR(at.focal_length_mm(), f, 1e-9 * f) << nm << " nm";
        // The microlenses' power scales with (n - 1) / (n_d - 1) = 1 + x / V_d.
        EXPECT_NEAR(at.array.microlens->focal_length_mm(0), 0.6 / (1 + x / 40), 1e-15) << nm << " nm";
        // Glass changes; the camera's build does not.
        EXPECT_EQ(at.distance_mm, d_line.distance_mm);
        EXPECT_EQ(at.sensor.z_mm, d_line.sensor.z_mm);
        EXPECT_EQ(at.array.pose.centre_mm.z, d_line.array.pose.centre_mm.z);
        EXPECT_EQ(at.prescription().surfaces[0].aperture_mm, d_line.prescription().surfaces[0].aperture_mm);
        EXPECT_TRUE(at.pupil_bounds != nullptr);
        EXPECT_NE(at.pupil_bounds, d_line.pupil_bounds) << "the bounds of the lens at that wavelength";
    }
    // Blue is refracted more: shorter focal length.
    EXPECT_LT(at_wavelength(d_line, 450).focal_length_mm(), at_wavelength(d_line, 650).focal_length_mm());
    // A lens and array that do not disperse are the same camera at every wavelength.
    const PlenopticCamera plain = make_camera(singlet_camera(0, 0));
    const PlenopticCamera blue = at_wavelength(plain, 420);
    EXPECT_EQ(blue.lens, plain.lens);
    EXPECT_EQ(blue.array.microlens, plain.array.microlens);
}

TEST(Spectral, CameraHoldsOneCameraPerBandWithItsFilm)
{
    CameraParams params = singlet_camera(30, 0);
    params.spectral.bands = 5;
    const PlenopticCamera camera = with_film(make_camera(params), 40, 30);
    ASSERT_TRUE(camera.spectral != nullptr);
    ASSERT_EQ(camera.spectral->cameras.size(), 5u);
    for (size_t b = 0; b < 5; ++b) {
        const PlenopticCamera& band = camera.spectral->cameras[b];
        EXPECT_EQ(band.sensor.film.width, 40);
        EXPECT_EQ(band.sensor.film.height, 30);
        EXPECT_TRUE(band.spectral == nullptr);
        EXPECT_NEAR(band.focal_length_mm(), at_wavelength(camera, camera.spectral->bands[b].wavelength_nm).focal_length_mm(),
                    1e-12);
    }
    EXPECT_TRUE(make_camera(singlet_camera(30, 0)).spectral == nullptr) << "no spectral cameras without spectral";
}

// Every sample passes and the scene is one colour: each band's value is that colour, so the
// spectral pixel is the colour itself when every band gets samples, and equals it in expectation
// over pixels when there are fewer samples than bands.
TEST(Spectral, GreyWorldPixelEqualsTheColourAndInExpectationWithFewSamples)
{
    CameraParams params = test::thin_lens_camera(50, 4, 60);
    params.spectral.bands = 8;
    const Rgbt grey{0.3, 0.3, 0.3, 0.0};
    auto scene = [&](const OpticsRay&) { return grey; };
    for (int samples : {8, 13, 24}) {
        params.sampling.samples = samples;
        const PlenopticCamera camera = with_film(make_camera(params), 64, 48);
        const Rgbt v = shade_pixel(camera, 32, 24, scene);
        EXPECT_NEAR(v.r, 0.3, 1e-12) << samples;
        EXPECT_NEAR(v.g, 0.3, 1e-12) << samples;
        EXPECT_NEAR(v.b, 0.3, 1e-12) << samples;
    }
    // 3 samples over 8 bands: one pixel sees 3 bands, scaled by 8/3; over many pixels the mean is
    // the colour. The pixel value's spread over the band offsets is known from the weights, so the
    // mean of 2400 pixels must land within 4 standard errors.
    params.sampling.samples = 3;
    const PlenopticCamera camera = with_film(make_camera(params), 60, 40);
    const std::vector<SpectralBand>& bands = camera.spectral->bands;
    for (int c = 0; c < 3; ++c) {
        // The pixel's value for each of the 8 offsets (3 consecutive bands, cyclically).
        double mean = 0, mean_sq = 0;
        for (int o = 0; o < 8; ++o) {
            double v = 0;
            for (int k = 0; k < 3; ++k)
                v += bands[size_t((o + k) % 8)].weight[c] * 0.3 * 8 / 3;
            mean += v / 8;
            mean_sq += v * v / 8;
        }
        ASSERT_NEAR(mean, 0.3, 1e-12);
        const double sd = std::sqrt(std::max(0.0, mean_sq - mean * mean));
        double sum = 0;
        int pixels = 0;
        for (int j = 0; j < 40; ++j)
            for (int i = 0; i < 60; ++i) {
                const Rgbt v = shade_pixel(camera, i, j, scene);
                sum += c == 0 ? v.r : c == 1 ? v.g : v.b;
                ++pixels;
            }
        EXPECT_GT(sd, 0.05) << "the pixels do differ (channel " << c << ")";
        EXPECT_NEAR(sum / pixels, 0.3, 4 * sd / std::sqrt(double(pixels))) << "channel " << c;
    }
}

TEST(Spectral, BandsShareThePixelsSamplesAndTheRenderIsDeterministic)
{
    CameraParams params = singlet_camera(25, 40);
    params.spectral.bands = 6;
    params.sampling.samples = 16;
    const PlenopticCamera camera = with_film(make_camera(params), 48, 36);
    int full = 0;
    for (int j = 0; j < 36; j += 5)
        for (int i = 0; i < 48; i += 5) {
            int calls = 0;
            const Rgbt a = shade_pixel(camera, i, j, [&](const OpticsRay& ray) {
                ++calls;
                return Rgbt{ray.dir.x + 0.5, ray.dir.y + 0.5, 0.5, 0};
            });
            const Rgbt b = shade_pixel(camera, i, j, [](const OpticsRay& ray) {
                return Rgbt{ray.dir.x + 0.5, ray.dir.y + 0.5, 0.5, 0};
            });
            EXPECT_EQ(a.r, b.r);
            EXPECT_EQ(a.g, b.g);
            EXPECT_EQ(a.b, b.b);
            // Scene rays: at most the pixel's 16 plus one per band for a band whose samples were all
            // blocked while its vignetting probes passed.
            EXPECT_LE(calls, 16 + 6);
            full += calls == 16;
        }
    EXPECT_GT(full, 0) << "pixels whose 16 samples all pass trace exactly 16 scene rays, shared among the bands";
}

} // namespace
} // namespace plenoptic
