// SPDX-License-Identifier: AGPL-3.0-or-later
// The thin lens's parametric distortion: the polynomial against values worked by hand, its inverse,
// the refusal of maps that fold over, and a distorted lens's rays: straight, reversible, landing
// on the ideal image's distorted position.

#include <cmath>

#include <gtest/gtest.h>

#include "plenoptic/lens/distortion.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/main_lens_params.h"

namespace plenoptic {
namespace {

TEST(Distortion, PolynomialMatchesHandWorkedValues)
{
    // (x, y) = (0.3, -0.2): r^2 = 0.13; radial factor 1 + 0.1*0.13 - 0.05*0.0169 + 0.02*0.002197
    // = 1.01219894; tangential with p1 = 0.01, p2 = -0.02:
    // dx = 2 p1 x y + p2 (r^2 + 2 x^2) = -0.0012 - 0.0062 = -0.0074
    // dy = p1 (r^2 + 2 y^2) + 2 p2 x y = 0.0021 + 0.0024 = 0.0045
    const DistortionParams d{{0.1, -0.05, 0.02}, {0.01, -0.02}};
    const Vec2 out = distort(d, Vec2{0.3, -0.2});
    EXPECT_NEAR(out.x, 0.3 * 1.01219894 - 0.0074, 1e-15);
    EXPECT_NEAR(out.y, -0.2 * 1.01219894 + 0.0045, 1e-15);
    const DistortionParams none{{0, 0, 0}, {0, 0}};
    EXPECT_TRUE(is_identity(none));
    EXPECT_FALSE(is_identity(d));
    EXPECT_EQ(distort(none, Vec2{0.3, -0.2}).x, 0.3);
}

TEST(Distortion, UndistortInvertsDistort)
{
    const DistortionParams cases[] = {{{-0.2, 0.05, 0}, {0, 0}}, {{0.1, -0.05, 0.02}, {0.01, -0.02}},
                                      {{0, 0, 0}, {0.003, 0.004}}};
    for (const DistortionParams& d : cases) {
        for (double x = -0.6; x <= 0.6; x += 0.1) {
            for (double y = -0.6; y <= 0.6; y += 0.15) {
                Vec2 back;
                ASSERT_TRUE(undistort(d, distort(d, Vec2{x, y}), &back)) << x << ", " << y;
                EXPECT_NEAR(back.x, x, 1e-12);
                EXPECT_NEAR(back.y, y, 1e-12);
            }
        }
    }
}

TEST(Distortion, RefusesMapsThatFoldOver)
{
    // Barrel k1 < 0: r (1 + k1 r^2) turns back at r^2 = -1 / (3 k1): k1 = -0.5 at r = 0.816.
    EXPECT_NE(check_distortion(DistortionParams{{-0.5, 0, 0}, {0, 0}}, 1.0), "");
    EXPECT_EQ(check_distortion(DistortionParams{{-0.3, 0, 0}, {0, 0}}, 1.0), "");  // turns at 1.054
    EXPECT_EQ(check_distortion(DistortionParams{{-0.5, 0, 0}, {0, 0}}, 0.8), "");
    EXPECT_NE(check_distortion(DistortionParams{{NAN, 0, 0}, {0, 0}}, 1.0), "");
    EXPECT_NE(check_distortion(DistortionParams{{0, 0, 0}, {0, INFINITY}}, 1.0), "");
}

// A distorted thin lens (F = 50, f/2, D = 60): the ray from a scene point through any point of
// the aperture crosses the plane z = -D at the distorted position of the ideal lens's image of
// that point there (for an in-focus point, every ray: the distorted image point).
TEST(Distortion, ThinLensRaysLandOnTheDistortedIdealImage)
{
    MainLensParams p;
    p.given = true;
    p.type = MainLensType::ThinLens;
    p.focal_length_mm = 50;
    p.has_f_number = true;
    p.f_number = 2;
    p.has_distortion = true;
    p.distortion = DistortionParams{{-0.15, 0.02, 0}, {0.002, -0.001}};
    const double D = 60;
    const std::shared_ptr<const MainLens> lens = make_main_lens(p, D);
    const double z = 50 * D / (D - 50);  // in focus on the plane: 300 mm
    for (double px : {0.0, 30.0, -80.0}) {
        for (double py : {0.0, 45.0, -20.0}) {
            const Vec3 point{px, py, z};
            // The ideal image on the plane: -point * D / z; its distorted position.
            const Vec2 ideal{-px * D / z / D, -py * D / z / D};
            const Vec2 real = distort(p.distortion, ideal);
            for (double ax : {-8.0, 0.0, 7.0}) {
                for (double ay : {-6.0, 0.0, 8.0}) {
                    const ImageRay out = lens->to_image(point, Vec3{ax, ay, 0} - point, true);
                    ASSERT_TRUE(out.passed) << px << " " << py << " " << ax << " " << ay << " dir " << out.dir.x << " " << out.dir.y << " " << out.dir.z;
                    const double t = (-D - out.origin.z) / out.dir.z;
                    EXPECT_NEAR(out.origin.x + t * out.dir.x, real.x * D, 1e-9);
                    EXPECT_NEAR(out.origin.y + t * out.dir.y, real.y * D, 1e-9);
                    // Back through to_scene from the plane: the ray returns to the point.
                    const Vec3 on_plane = out.origin + t * out.dir;
                    const SceneRay back = lens->to_scene(on_plane, out.origin - on_plane, true);
                    ASSERT_TRUE(back.passed);
                    const Vec3 rel = point - back.origin;
                    EXPECT_LT(length(cross(rel, back.dir)), 1e-7 * length(rel));
                }
            }
        }
    }
}

} // namespace
} // namespace plenoptic
