// SPDX-License-Identifier: AGPL-3.0-or-later
// Virtual depth against the thin-lens equation written out here: a point at z images at
// b = F z / (z - F) behind the lens; the array is at D, the sensor d behind it; a = D - b is the
// image's distance in front of the array and v = -a / d (libpleno's sign: Galilean images, behind
// the array, have v > 0).

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "plenoptic/camera/rays.h"
#include "plenoptic/core/test_util.h"
#include "plenoptic/truth/virtual_depth.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;

const double F = 50, D = 55, PITCH = 0.2;

double thin_lens_v(double z, double d)
{
    const double b = F * z / (z - F);
    return -(D - b) / d;
}

TEST(VirtualDepth, FocusedCamerasOnly)
{
    EXPECT_FALSE(is_focused_camera(make_camera(plenoptic_camera(GridType::Hexagonal, PITCH, 0.6, 0.6, F, 4, D))));
    EXPECT_TRUE(is_focused_camera(make_camera(plenoptic_camera(GridType::Hexagonal, PITCH, 0.6, 0.9, F, 4, D))));
    EXPECT_TRUE(is_focused_camera(make_camera(plenoptic_camera(GridType::Rectangular, PITCH, 0.9, 0.6, F, 4, D))));
    CameraParams multi = plenoptic_camera(GridType::Hexagonal, PITCH, 0.6, 0.6, F, 4, D);
    multi.array.focal_length_count = 3;
    multi.array.focal_lengths_mm[1] = 0.7;
    multi.array.focal_lengths_mm[2] = 0.8;
    EXPECT_TRUE(is_focused_camera(make_camera(multi)));
    CameraParams pinholes = plenoptic_camera(GridType::Hexagonal, PITCH, 0.6, 0.9, F, 4, D);
    pinholes.array.lens = MicrolensType::Pinhole;
    pinholes.array.focal_length_count = 0;
    EXPECT_FALSE(is_focused_camera(make_camera(pinholes)));
}

TEST(VirtualDepth, PointsAgainstTheThinLensEquation)
{
    for (double d : {0.9, 0.4}) {  // Keplerian (d > f = 0.6) and Galilean (d < f)
        const PlenopticCamera m = make_camera(plenoptic_camera(GridType::Hexagonal, PITCH, 0.6, d, F, 4, D));
        for (double z : {300.0, 550.0, 1000.0, 5000.0, 1e6})
            for (double x : {0.0, 40.0, -120.0}) {
                const double v = virtual_depth(m, Vec3{x, 0.5 * x, z});
                EXPECT_NEAR(v, thin_lens_v(z, d), 1e-9 * std::fabs(thin_lens_v(z, d)) + 1e-9) << d << " " << z << " " << x;
            }
        // In focus on the array (z = F D / (D - F) = 550 mm): v = 0; nearer: behind the array.
        EXPECT_NEAR(virtual_depth(m, Vec3{0, 0, F * D / (D - F)}), 0, 1e-9);
        EXPECT_GT(virtual_depth(m, Vec3{0, 0, 400}), 0);
        EXPECT_LT(virtual_depth(m, Vec3{0, 0, 2000}), 0);
        // On the front focal plane the image is at infinity.
        EXPECT_TRUE(std::isnan(virtual_depth(m, Vec3{0, 0, F})));
    }
}

TEST(VirtualDepth, TiltedArrayMeasuresAlongItsNormal)
{
    CameraParams p = plenoptic_camera(GridType::Rectangular, PITCH, 0.6, 0.9, F, 4, D);
    test::set_pose(&p, 10, -5, 30, 0.3, -0.2, 0.1);
    const PlenopticCamera m = make_camera(p);
    const double deg[3] = {10, -5, 30};
    const Vec3 normal = test::reference_rotate(deg, Vec3{0, 0, 1});
    const Vec3 centre{0.3, -0.2, -D + 0.1};
    for (double z : {400.0, 900.0}) {
        const Vec3 point{25, -10, z};
        const double scale = -F / (z - F);  // the thin lens images (x, y, z) at scale * (x, y, z)
        const Vec3 image{point.x * scale, point.y * scale, -F * z / (z - F)};
        const double a = normal.x * (image.x - centre.x) + normal.y * (image.y - centre.y) + normal.z * (image.z - centre.z);
        EXPECT_NEAR(virtual_depth(m, point), -a / effective_array_distance_mm(m), 1e-9) << z;
    }
}

TEST(VirtualDepth, PixelsOfAFrontoParallelPlane)
{
    // The depth map's distance to a plane at z (mm) along pixel (i, j)'s chief ray is
    // (z - o_z) / w_z in scene units; its virtual depth is the plane's, whatever the pixel.
    const double d = 0.9;
    const PlenopticCamera m = make_camera(plenoptic_camera(GridType::Hexagonal, PITCH, 0.6, d, F, 4, D));
    const int W = 64, H = 48;
    for (double z : {350.0, 800.0, 3000.0})
        for (int j = 0; j < H; j += 7)
            for (int i = 0; i < W; i += 5) {
                const OpticsRay ray = with_film(m, W, H).chief_ray(i, j);
                const float distance = float((z - ray.origin_mm.z) / ray.dir.z / m.mm_per_unit);
                EXPECT_NEAR(pixel_virtual_depth(with_film(m, W, H), i, j, distance), thin_lens_v(z, d),
                            2e-5 * std::fabs(thin_lens_v(z, d)) + 1e-5) << z << " " << i << " " << j;
            }
    // Nothing hit: the point at infinity images on the focal plane, v = (F - D) / d.
    EXPECT_NEAR(pixel_virtual_depth(with_film(m, W, H), 10, 10, std::numeric_limits<float>::infinity()), (F - D) / d, 1e-5);
    // A blocked pixel (-1) has none.
    EXPECT_TRUE(std::isnan(pixel_virtual_depth(with_film(m, W, H), 10, 10, -1.0f)));
}

}  // namespace
}  // namespace plenoptic
