// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the distortion profile against closed forms: an ideal thin lens has none (its chief
// rays go straight through its centre to the paraxial image); a thin lens with radial distortion
// moves the image to h (1 + k1 r^2 + k2 r^4 + k3 r^6), r = h / D; the paraxial thick lens has none;
// a traced singlet with the stop in front shows distortion of the sign the stop position gives
// (a stop in front of a positive lens: barrel, real < paraxial), its chief rays crossing the
// stop's centre. The traced lens's values against an independent tracer are in
// tests/optics/test_distortion_profile.py.

#include <cmath>

#include <gtest/gtest.h>

#include "plenoptic/truth/distortion_profile.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {


using test::thin_lens_camera;

TEST(DistortionProfile, IdealThinLensHasNone)
{
    CameraParams p = thin_lens_camera(50, 4, 60);
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.02;
    const PlenopticCamera m = with_film(make_camera(p), 1200, 800);
    const DistortionProfile profile = distortion_profile(m, 17);
    ASSERT_TRUE(profile.valid);
    ASSERT_EQ(profile.samples.size(), 17u);
    EXPECT_FALSE(profile.object_at_infinity);
    EXPECT_NEAR(profile.object_plane_z_mm, 50.0 * 60 / (60 - 50), 1e-9);  // 1/s + 1/D = 1/F
    EXPECT_EQ(profile.image_plane_z_mm, -60);
    const double corner = std::hypot(600 * 0.02, 400 * 0.02);
    EXPECT_NEAR(profile.samples.back().paraxial_height_mm, corner, 1e-12);
    for (const DistortionSample& s : profile.samples) {
        EXPECT_NEAR(s.real_height_mm, s.paraxial_height_mm, 1e-9);
        // Through the lens centre: the image-side angle equals the object-side one.
        EXPECT_NEAR(s.field_angle_deg, std::atan(s.paraxial_height_mm / 60) * 180 / kPi, 1e-9);
    }
}

TEST(DistortionProfile, ThinLensRadialDistortionFollowsThePolynomial)
{
    CameraParams p = thin_lens_camera(50, 4, 60);
    p.main.has_distortion = true;
    p.main.distortion = DistortionParams{{-0.12, 0.03, -0.004}, {0, 0}};
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.02;
    const PlenopticCamera m = with_film(make_camera(p), 1200, 800);
    const DistortionProfile profile = distortion_profile(m, 9);
    ASSERT_TRUE(profile.valid);
    ASSERT_EQ(profile.samples.size(), 9u);
    for (const DistortionSample& s : profile.samples) {
        const double r = s.paraxial_height_mm / 60;
        const double expected = s.paraxial_height_mm * (1 - 0.12 * r * r + 0.03 * std::pow(r, 4) - 0.004 * std::pow(r, 6));
        EXPECT_NEAR(s.real_height_mm, expected, 1e-9) << s.relative_field;
    }
    EXPECT_LT(profile.samples.back().real_height_mm, profile.samples.back().paraxial_height_mm);  // barrel
}

// A biconvex singlet (n = 1.5, R = +-100 mm, 5 mm thick: F ~ 101 mm) with the stop `gap` mm in
// front of it (or behind it, gap < 0).
Prescription singlet_with_stop(double gap)
{
    Prescription lens;
    if (gap > 0)
        lens.surfaces.push_back(LensSurface{0, gap, 1, 10, true, 1});
    lens.surfaces.push_back(LensSurface{100, 5, 1.5, 40, false, 2});
    lens.surfaces.push_back(LensSurface{-100, gap < 0 ? -gap : 0, 1, 40, false, 3});
    if (gap < 0)
        lens.surfaces.push_back(LensSurface{0, 0, 1, 10, true, 4});
    return lens;
}

PlenopticCamera singlet_camera(double gap, MainLensType type)
{
    const Prescription lens = singlet_with_stop(gap);
    CameraParams p = thin_lens_camera(50, 4, 0);
    p.main.type = type;
    p.main.has_focal_length = false;
    p.main.has_f_number = false;
    p.main.has_prescription = true;
    p.main.prescription = lens;
    const ImageDistance focus = paraxial_image_distance(lens, 2000);
    p.main.distance_mm = focus.mm;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.02;
    return make_camera(p);
}

TEST(DistortionProfile, StopPositionGivesTheSignOfASinglesDistortion)
{
    // Stop in front of a positive lens: barrel; behind it: pincushion. The thick-lens model of
    // the same prescription (paraxial) has none.
    const PlenopticCamera front = with_film(singlet_camera(20, MainLensType::Prescription), 1500, 1000);
    const PlenopticCamera behind = with_film(singlet_camera(-20, MainLensType::Prescription), 1500, 1000);
    const PlenopticCamera thick = with_film(singlet_camera(20, MainLensType::ThickLens), 1500, 1000);
    ASSERT_EQ(test::lens_kind(front), "prescription");
    const DistortionProfile a = distortion_profile(front, 9);
    const DistortionProfile b = distortion_profile(behind, 9);
    const DistortionProfile c = distortion_profile(thick, 9);
    ASSERT_TRUE(a.valid && b.valid && c.valid);
    ASSERT_EQ(a.samples.size(), 9u);
    ASSERT_EQ(b.samples.size(), 9u);
    EXPECT_EQ(a.samples[0].real_height_mm, 0);
    for (std::size_t i = 1; i < a.samples.size(); ++i) {
        EXPECT_LT(a.samples[i].real_height_mm, a.samples[i].paraxial_height_mm) << i;
        EXPECT_GT(b.samples[i].real_height_mm, b.samples[i].paraxial_height_mm) << i;
        EXPECT_NEAR(c.samples[i].real_height_mm, c.samples[i].paraxial_height_mm, 1e-9 * c.samples[i].paraxial_height_mm) << i;
    }
    // Small fields converge to the paraxial image (third-order distortion grows as h^3).
    const double small = a.samples[1].real_height_mm / a.samples[1].paraxial_height_mm - 1;
    const double large = a.samples[8].real_height_mm / a.samples[8].paraxial_height_mm - 1;
    EXPECT_NEAR(small / large, 1.0 / 64, 0.3 / 64);
}

TEST(DistortionProfile, NoneWithoutARealObjectOrALens)
{
    CameraParams inside = thin_lens_camera(50, 4, 40);  // D < F: no real object images onto z = -D
    EXPECT_FALSE(distortion_profile(with_film(make_camera(inside), 100, 100), 9).valid);
    CameraParams at_focus = thin_lens_camera(50, 4, 50);
    const DistortionProfile infinity = distortion_profile(with_film(make_camera(at_focus), 100, 100), 9);
    ASSERT_TRUE(infinity.valid);
    EXPECT_TRUE(infinity.object_at_infinity);
    for (const DistortionSample& s : infinity.samples)
        EXPECT_NEAR(s.real_height_mm, s.paraxial_height_mm, 1e-9);
}

} // namespace
} // namespace plenoptic
