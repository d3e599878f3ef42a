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

// The two-term index (lens/glass.h's model, written here) of n_d 1.5, V_d 20.
double index_at_nm(double nm) { return 1.5 + 0.5 / 20 * (523655.0 / (nm * nm) - 1.5168); }

TEST(DistortionProfile, ChannelsOfADispersingSingletFollowTheParaxialChiefRayAtTheirIndex)
{
    // The singlet with the stop 20 mm in front, its glass dispersing (V_d 20). Traced at another
    // wavelength, the same object points' chief rays (through the stop's centre, same field
    // angle) meet the d line's image plane at heights that a paraxial y-u trace at that index
    // gives for small fields. Written here: from the stop (y = 0) at slope u = tan(angle), over the
    // gap, refraction n u' = u - y (n - 1) / R1, the thickness, u'' = n u' - y (1 - n) / R2, then D
    // to the image plane.
    Prescription lens = singlet_with_stop(20);
    lens.surfaces[1].glass.abbe = 20;
    CameraParams p = thin_lens_camera(50, 4, 0);
    test::use_prescription(&p, lens);
    p.main.distance_mm = paraxial_image_distance(lens, 2000).mm;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.02;
    const PlenopticCamera d_line = with_film(make_camera(p), 1500, 1000);
    const double D = d_line.distance_mm;
    const DistortionProfile own = distortion_profile(d_line, 33);
    ASSERT_TRUE(own.valid);
    double lateral[2] = {0, 0};
    int which = 0;
    for (double nm : {450.0, 650.0}) {
        const PlenopticCamera at = at_wavelength(d_line, nm);
        const DistortionProfile profile = distortion_profile(d_line, 33, &at);
        ASSERT_TRUE(profile.valid);
        ASSERT_EQ(profile.samples.size(), own.samples.size());
        const double n = index_at_nm(nm);
        for (int i : {1, 2}) {  // small fields: third-order terms below 1e-3 of the height
            const DistortionSample& s = profile.samples[size_t(i)];
            EXPECT_EQ(s.paraxial_height_mm, own.samples[size_t(i)].paraxial_height_mm);
            EXPECT_NEAR(s.field_angle_deg, own.samples[size_t(i)].field_angle_deg, 1e-9) << "the same object point";
            const double u0 = std::tan(s.field_angle_deg * kPi / 180);
            const double y1 = 20 * u0;
            const double u1 = (u0 - y1 * (n - 1) / 100) / n;
            const double y2 = y1 + 5 * u1;
            const double u2 = n * u1 - y2 * (1 - n) / -100;
            const double y3 = y2 + D * u2;
            EXPECT_NEAR(s.real_height_mm, std::fabs(y3), 2e-3 * std::fabs(y3)) << nm << " nm, row " << i;
        }
        lateral[which++] = profile.samples[2].real_height_mm;
    }
    // Lateral colour: blue refracted more; with the stop in front it lands nearer the axis here.
    EXPECT_NE(lateral[0], lateral[1]);
    EXPECT_LT(lateral[0], own.samples[2].real_height_mm);
    EXPECT_GT(lateral[1], own.samples[2].real_height_mm);
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
