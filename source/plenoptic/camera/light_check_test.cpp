// SPDX-License-Identifier: AGPL-3.0-or-later
// Parameters that leave the image black were silent. The lit fraction is
// checked against the geometry of an f-number-matched plenoptic 1.0 camera, where the main
// lens's image through each microlens is a disc of radius (A/2) d/D in a p x p cell.

#include <gtest/gtest.h>

#include "plenoptic/camera/light_check.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {



CameraParams plenoptic_1_0(double f_number)
{
    // F = 16 mm focused at 2 m: D = 16 * 2000 / (2000 - 16); microlenses f = d = 0.6 mm, p = 0.15 mm.
    CameraParams p = test::plenoptic_camera(GridType::Rectangular, 0.15, 0.6, 0.6, 16, f_number, 16.0 * 2000 / 1984);
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.005;
    return p;
}

TEST(LightCheck, LitFractionIsTheMicroimageDiscOverItsCell)
{
    for (double f_number : {6.0, 8.0, 16.0}) {
        const PlenopticCamera m = make_camera(plenoptic_1_0(f_number));
        const double radius = 0.5 * (16 / f_number) * 0.6 / m.distance_mm;
        const double expected = kPi * radius * radius / (0.15 * 0.15);
        const double measured = lit_fraction_near_axis(m);
        // 16 points per pixel over a patch of whole pixels: the rim of a disc a few pixels
        // across is resolved to about a fifth of its area at f/16.
        EXPECT_NEAR(measured, expected, 0.2 * expected) << "f/" << f_number;
        EXPECT_EQ(dark_image_warning(m), "") << "f/" << f_number;
    }
}

TEST(LightCheck, TinyApertureWarns)
{
    const PlenopticCamera m = make_camera(plenoptic_1_0(1e6));
    EXPECT_LT(lit_fraction_near_axis(m), kDarkImageFraction);
    const std::string message = dark_image_warning(m);
    EXPECT_NE(message.find("black"), std::string::npos) << message;
    EXPECT_NE(message.find("f-number 1000000"), std::string::npos) << message;
}

TEST(LightCheck, FocusAtTheFocalLengthWarns)
{
    CameraParams p = plenoptic_1_0(4);
    p.main.has_distance = false;
    p.main.has_focus_distance = true;
    p.main.focus_distance_units = 0.016 + 1e-9;  // 1e-6 mm beyond F = 16 mm
    ASSERT_EQ(check_camera(p), "");
    const PlenopticCamera m = make_camera(p);
    EXPECT_GT(m.distance_mm, 1e7);
    EXPECT_LT(lit_fraction_near_axis(m), kDarkImageFraction);
    EXPECT_NE(dark_image_warning(m).find("black"), std::string::npos) << dark_image_warning(m);
}

TEST(LightCheck, CamerasWithoutDarknessStayQuiet)
{
    EXPECT_EQ(dark_image_warning(make_camera(test::thin_lens_camera(50, 1e6, 52))), "");  // samples aim at the disc
    CameraParams array_only;
    test::add_array(&array_only, GridType::Hexagonal, 0.1, 0, 0.4);
    EXPECT_GT(lit_fraction_near_axis(make_camera(array_only)), 0.9);
}

} // namespace
} // namespace plenoptic
