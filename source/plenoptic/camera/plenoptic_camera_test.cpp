// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the precomputed model: distances, pose convention, overlap decision, warnings.

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;
using test::thin_lens_camera;

bool any_contains(const std::vector<std::string>& list, const std::string& part)
{
    for (const std::string& s : list)
        if (s.find(part) != std::string::npos)
            return true;
    return false;
}

TEST(Model, DistanceFromFocusDistanceObeysTheThinLensEquation)
{
    for (double focus : {0.0500001, 0.1, 2.5, 1e3, 1e300}) {
        CameraParams p = thin_lens_camera(50, 4, 0);
        p.main.has_distance = false;
        p.main.has_focus_distance = true;
        p.main.focus_distance_units = focus;
        ASSERT_EQ(check_camera(p), "") << focus;
        const PlenopticCamera m = make_camera(p);
        const double z = focus * 1000;
        // 1/F = 1/z + 1/D
        EXPECT_NEAR(1 / m.distance_mm + 1 / z, 1 / 50.0, 1e-15) << "focus " << focus << " D " << m.distance_mm;
        EXPECT_TRUE(std::isfinite(m.distance_mm));
        EXPECT_TRUE(m.has_focus_distance);
        EXPECT_EQ(m.sensor.z_mm, -m.distance_mm);
    }
}

TEST(Model, ApertureAndFNumber)
{
    PlenopticCamera m = make_camera(thin_lens_camera(50, 4, 52));
    EXPECT_DOUBLE_EQ(m.aperture_mm(), 12.5);
    EXPECT_DOUBLE_EQ(m.f_number(), 4);
    CameraParams p = thin_lens_camera(50, 4, 52);
    p.main.has_f_number = false;
    p.main.has_aperture = true;
    p.main.aperture_mm = 25;
    m = make_camera(p);
    EXPECT_DOUBLE_EQ(m.f_number(), 2);
}

TEST(Model, PlanesOfEachConfiguration)
{
    PlenopticCamera m = make_camera(plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52));
    EXPECT_DOUBLE_EQ(m.array.pose.centre_mm.z, -52);
    EXPECT_DOUBLE_EQ(m.sensor.z_mm, -54);

    CameraParams bare;
    test::add_array(&bare, GridType::Rectangular, 0.5, 0, 2);
    m = make_camera(bare);
    EXPECT_EQ(test::lens_kind(m), "none");
    EXPECT_DOUBLE_EQ(m.array.pose.centre_mm.z, 0);
    EXPECT_DOUBLE_EQ(m.sensor.z_mm, -2);

    m = make_camera(thin_lens_camera(50, 4, 52));
    EXPECT_EQ(m.array.grid, GridType::None);
    EXPECT_DOUBLE_EQ(m.sensor.z_mm, -52);

    // The array's translation moves the array only, not the sensor.
    CameraParams moved = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52);
    test::set_pose(&moved, 0, 0, 0, 0.1, -0.2, 0.3);
    m = make_camera(moved);
    EXPECT_DOUBLE_EQ(m.array.pose.centre_mm.x, 0.1);
    EXPECT_DOUBLE_EQ(m.array.pose.centre_mm.y, -0.2);
    EXPECT_DOUBLE_EQ(m.array.pose.centre_mm.z, -51.7);
    EXPECT_DOUBLE_EQ(m.sensor.z_mm, -54);
    EXPECT_NEAR(effective_main_distance_mm(m), 51.7, 1e-12);
    EXPECT_NEAR(effective_array_distance_mm(m), 2.3, 1e-12);
}

TEST(Model, RotationFollowsPovRayConvention)
{
    // POV-Ray builds row-vector matrices Mx * My * Mz and transforms p -> p M. Rebuild that here,
    // with its element layout ([1][2] = sin x, [0][2] = -sin y, [0][1] = sin z), and compare.
    const double angles[][3] = {{10, 0, 0}, {0, 20, 0}, {0, 0, 30}, {10, -20, 30}, {89.99, 45, -170}};
    for (const auto& deg : angles) {
        const double rad = kPi / 180;
        const double cx = std::cos(deg[0] * rad), sx = std::sin(deg[0] * rad);
        const double cy = std::cos(deg[1] * rad), sy = std::sin(deg[1] * rad);
        const double cz = std::cos(deg[2] * rad), sz = std::sin(deg[2] * rad);
        double mx[3][3] = {{1, 0, 0}, {0, cx, sx}, {0, -sx, cx}};
        double my[3][3] = {{cy, 0, -sy}, {0, 1, 0}, {sy, 0, cy}};
        double mz[3][3] = {{cz, sz, 0}, {-sz, cz, 0}, {0, 0, 1}};
        double xy[3][3] = {}, xyz[3][3] = {};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                for (int k = 0; k < 3; ++k)
                    xy[i][j] += mx[i][k] * my[k][j];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                for (int k = 0; k < 3; ++k)
                    xyz[i][j] += xy[i][k] * mz[k][j];
        const Mat3 r = rotation_from_degrees(deg);
        const Vec3 v{0.3, -1.2, 2.5};
        const Vec3 ours = mul(r, v);
        const Vec3 pov{v.x * xyz[0][0] + v.y * xyz[1][0] + v.z * xyz[2][0],
                       v.x * xyz[0][1] + v.y * xyz[1][1] + v.z * xyz[2][1],
                       v.x * xyz[0][2] + v.y * xyz[1][2] + v.z * xyz[2][2]};
        const Vec3 reference = test::reference_rotate(deg, v);
        EXPECT_NEAR(ours.x, pov.x, 1e-12) << deg[0] << "," << deg[1] << "," << deg[2];
        EXPECT_NEAR(ours.y, pov.y, 1e-12);
        EXPECT_NEAR(ours.z, pov.z, 1e-12);
        EXPECT_NEAR(ours.x, reference.x, 1e-12);
        EXPECT_NEAR(ours.y, reference.y, 1e-12);
        EXPECT_NEAR(ours.z, reference.z, 1e-12);
    }
    // Rotating +x by +90 degrees about z gives +y (right-hand rule, as POV-Ray's numbers).
    const double quarter[3] = {0, 0, 90};
    const Vec3 y = mul(rotation_from_degrees(quarter), Vec3{1, 0, 0});
    EXPECT_EQ(y.x, 0.0);
    EXPECT_EQ(y.y, 1.0);
    // Multiples of 90 degrees and 360 are exact.
    const double turns[3] = {360, -180, 720};
    const Mat3 r = rotation_from_degrees(turns);
    EXPECT_EQ(r.m[0][2], 0.0);
    EXPECT_EQ(r.m[1][2], 0.0);
    EXPECT_EQ(r.m[2][2], -1.0);
}

TEST(Model, TiltFlagOnlyForRotationAboutXOrY)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52);
    test::set_pose(&p, 0, 0, 37, 0, 0, 0);
    EXPECT_FALSE(make_camera(p).array.pose.tilted);
    test::set_pose(&p, 1e-9, 0, 0, 0, 0, 0);
    EXPECT_TRUE(make_camera(p).array.pose.tilted);
    test::set_pose(&p, 0, 360, 0, 0, 0, 0);
    EXPECT_FALSE(make_camera(p).array.pose.tilted);
}

TEST(Model, OverlapDecision)
{
    // Plenoptic 1.0, hexagonal, pitch 0.1, f = d = 0.5 (microlens f-number 5).
    // Main lens at twice the matched f-number: microimages stay apart.
    PlenopticCamera m = make_camera(plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 10, 50));
    EXPECT_FALSE(m.overlap.modelled);
    EXPECT_TRUE(warnings(m).empty()) << warnings(m)[0];
    // Matched: the cell corners spill a little; modelled, without a warning.
    m = make_camera(plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 5, 50));
    EXPECT_TRUE(m.overlap.modelled);
    EXPECT_GE(m.overlap.rings, 1);
    EXPECT_FALSE(any_contains(warnings(m), "overlap"));
    // Half the matched f-number: real overlap, with a warning that names the cure.
    m = make_camera(plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 2.5, 50));
    EXPECT_TRUE(m.overlap.modelled);
    EXPECT_GE(m.overlap.rings, 2);
    const std::vector<std::string> w = warnings(m);
    EXPECT_TRUE(any_contains(w, "microimages overlap")) << (w.empty() ? "no warning" : w[0]);
    EXPECT_TRUE(any_contains(w, "f_number of at least")) << (w.empty() ? "no warning" : w[0]);
    // No main lens: a baffled camera array, never overlap.
    CameraParams bare;
    test::add_array(&bare, GridType::Hexagonal, 0.1, 0.5, 0.5);
    EXPECT_FALSE(make_camera(bare).overlap.modelled);
    // A huge aperture asks for more rings than modelled: capped, with a warning.
    m = make_camera(plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 0.1, 50));
    EXPECT_TRUE(m.overlap.rings_capped);
    EXPECT_EQ(m.overlap.rings, kMaxOverlapRings);
    EXPECT_TRUE(any_contains(warnings(m), "ignored"));
}

TEST(Model, WarnsAboutTinyMicroimages)
{
    CameraParams p = plenoptic_camera(GridType::Rectangular, 0.015, 0.075, 0.075, 50, 20, 50);
    const std::vector<std::string> w = warnings(make_camera(p));
    EXPECT_TRUE(any_contains(w, "pixels apart")) << (w.empty() ? "no warning" : w[0]);
}

TEST(Model, AdaptiveSamplingTable)
{
    CameraParams p = thin_lens_camera(50, 4, 52);
    p.sampling.adaptive = true;
    p.sampling.samples_min = 4;
    p.sampling.samples_max = 64;
    const PlenopticCamera m = make_camera(p);
    EXPECT_TRUE(m.sampling.adaptive);
    EXPECT_EQ(m.sampling.samples_min, 4);
    EXPECT_EQ(m.sampling.samples_max, 64);
    ASSERT_EQ(m.sampling.thresholds.size(), 64u);
    EXPECT_NEAR(m.sampling.thresholds[62], 1.0 / 128, 1e-15);

    p.sampling = SamplingParams();
    p.sampling.samples = 9;
    const PlenopticCamera fixed = make_camera(p);
    EXPECT_FALSE(fixed.sampling.adaptive);
    EXPECT_EQ(fixed.sampling.samples_min, 9);
    EXPECT_EQ(fixed.sampling.samples_max, 9);
}

TEST(Model, OmittedSamplesDependOnWhetherAnApertureIsSampled)
{
    // A thin main lens alone, or thin microlenses: the aperture needs samples.
    EXPECT_EQ(make_camera(thin_lens_camera(50, 4, 52)).sampling.samples_max, kDefaultSamplesApertures);
    const CameraParams thin_array = plenoptic_camera(GridType::Hexagonal, 0.1, 0.4, 0.4, 50, 4, 52);
    EXPECT_EQ(make_camera(thin_array).sampling.samples_max, kDefaultSamplesApertures);
    EXPECT_EQ(make_camera(thin_array).sampling.samples_min, kDefaultSamplesApertures);
    EXPECT_FALSE(make_camera(thin_array).sampling.adaptive);
    // Pinhole microlenses behind a thin main lens: one ray per point of the pixel.
    EXPECT_EQ(make_camera(plenoptic_camera(GridType::Hexagonal, 0.1, 0, 0.4, 50, 4, 52)).sampling.samples_max,
              kDefaultSamplesPinholes);
    // A given count always wins.
    CameraParams given = thin_array;
    given.sampling.samples = 3;
    EXPECT_EQ(make_camera(given).sampling.samples_max, 3);
    EXPECT_TRUE(check_camera(thin_array).empty()) << check_camera(thin_array);
}

} // namespace
} // namespace plenoptic
