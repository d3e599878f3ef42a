// SPDX-License-Identifier: AGPL-3.0-or-later
// The blur radius against rays traced here: the main lens's image X' of a point (thin-lens
// equation), the ray from X' to the rim of a microlens, bent there by the thin-lens rule
// (slope change -h / f), carried to the sensor; its distance from the ray through the lens
// centre is the blur disc's radius. The sign: positive when the rays cross in front of the sensor.

#include <gtest/gtest.h>

#include <cmath>

#include "plenoptic/truth/blur.h"
#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;

const double F = 50, D = 52, PITCH = 0.3, PIXEL = 0.01;

// Radius (mm) of the disc through a lens at lateral position cx (on the array plane, z = -D) of
// the image point X' = (xi, zi) (zi < 0 behind the main lens), array to sensor d, focal length f;
// signed: positive when the rim ray has crossed the centre ray before the sensor.
double traced_radius(double xi, double zi, double cx, double f, double d)
{
    const double rim = cx + 0.5 * PITCH;
    // Slopes dx/dz along the direction of travel (towards -z).
    const double centre_slope = (cx - xi) / (-D - zi);
    const double rim_slope = (rim - xi) / (-D - zi) - (rim - cx) / f * -1.0;  // travelling towards -z
    const double at_sensor_centre = cx + centre_slope * -d;
    const double at_sensor_rim = rim + rim_slope * -d;
    // Before crossing, the rim ray is on the rim's side (+x of the centre ray): negative radius.
    return -(at_sensor_rim - at_sensor_centre);
}

TEST(Blur, FocusedLensesAgainstTracedRays)
{
    for (double d : {0.75, 0.35}) {
        CameraParams p = plenoptic_camera(GridType::Rectangular, PITCH, 0.5, d, F, 2, D);
        p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = PIXEL;
        const PlenopticCamera m = make_camera(p);
        for (double z : {700.0, 1000.0, 1200.0, 1500.0, 2500.0, 1e5})  // not 1300: b = D
            for (int k : {0, 3, -2}) {
                const LensIndex lens{k, 1};
                const Vec3 c = lens_centre_mm(m, lens);
                const Vec3 point{c.x * -z / D, 0, z};  // on the line through the lens centre
                const double b = F * z / (z - F);
                const double xi = -point.x * b / z;
                const double expected = traced_radius(xi, -b, c.x, 0.5, d) / PIXEL;
                EXPECT_NEAR(blur_radius_px(m, point, lens), expected, 1e-6 * std::fabs(expected) + 1e-9)
                    << "d " << d << " z " << z << " k " << k;
                // libpleno's closed form, with a = D - b.
                const double a = D - b;
                EXPECT_NEAR(blur_radius_px(m, point, lens), 0.5 * PITCH * d * (1 / 0.5 - 1 / a - 1 / d) / PIXEL, 1e-9);
            }
    }
}

TEST(Blur, MultiFocusTypesAndInfinity)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, PITCH, 0.5, 0.7, F, 2, D);
    p.array.focal_length_count = 3;
    p.array.focal_lengths_mm[1] = 0.6;
    p.array.focal_lengths_mm[2] = 0.8;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = PIXEL;
    const PlenopticCamera m = make_camera(p);
    const Vec3 point{10, -5, 2000};
    const double b = F * 2000 / (2000 - F);
    for (int k = 0; k < 6; ++k) {
        const LensIndex lens{k, 2};
        const double f = p.array.focal_lengths_mm[lens_type(lens, 3)];
        EXPECT_NEAR(blur_radius_px(m, point, lens), 0.5 * PITCH * 0.7 * (1 / f - 1 / (D - b) - 1 / 0.7) / PIXEL, 1e-9);
    }
    // On the front focal plane the main lens images the point at infinity: 1/a = 0.
    const Vec3 focal{1, 1, F};
    EXPECT_NEAR(blur_radius_px(m, focal, LensIndex{0, 0}), 0.5 * PITCH * 0.7 * (1 / 0.5 - 1 / 0.7) / PIXEL, 1e-6);
}

TEST(Blur, WithoutArrayAndPinholes)
{
    // The thin lens alone: aperture radius A/2 = F / N / 2, sensor at D: (A/2)(D / b - 1).
    CameraParams lens_only = test::thin_lens_camera(F, 2, D);
    lens_only.sensor.pixel_size_mm[0] = lens_only.sensor.pixel_size_mm[1] = PIXEL;
    const PlenopticCamera m = make_camera(lens_only);
    for (double z : {600.0, 1300.0, 4000.0}) {
        const Vec3 point{30, 20, z};
        const double b = F * z / (z - F);
        EXPECT_NEAR(blur_radius_px(m, point, LensIndex{0, 0}), 0.5 * F / 2 * (D / b - 1) / PIXEL, 1e-6) << z;
    }
    CameraParams pinholes = plenoptic_camera(GridType::Hexagonal, PITCH, 0.5, 0.7, F, 2, D);
    pinholes.array.lens = MicrolensType::Pinhole;
    pinholes.array.focal_length_count = 0;
    const Vec3 point{0, 0, 900};
    EXPECT_EQ(blur_radius_px(make_camera(pinholes), point, LensIndex{0, 0}), 0);
}

}  // namespace
}  // namespace plenoptic
