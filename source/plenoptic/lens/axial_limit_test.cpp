// SPDX-License-Identifier: AGPL-3.0-or-later
// The aperture that limits the axial beam (docs/real-lenses.md, "Which aperture limits the
// beam"): which one, the pupils and f-numbers computed from it, the refusal of a stop the lens
// cannot deliver and the warning for a stop written wider than the elements. The answers are
// worked here in closed form: marginal-ray heights in air and in one glass, the thick-lens
// formulas and the image of a point through one spherical surface.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "plenoptic/lens/main_lens.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/sensor/white_image.h"

namespace plenoptic {
namespace {

// A stop of diameter `stop` 10 mm in front of a biconvex singlet (R1 = 100, R2 = -100, n = 1.5,
// t = 5) whose surfaces have clear apertures a1 and a2.
const double kN = 1.5, kR1 = 100, kR2 = -100, kT = 5, kGap = 10;

Prescription stop_and_singlet(double stop, double a1, double a2)
{
    Prescription lens;
    lens.surfaces.push_back(LensSurface{0, kGap, 0, stop, true, 11});
    lens.surfaces.push_back(LensSurface{kR1, kT, kN, a1, false, 12});
    lens.surfaces.push_back(LensSurface{kR2, 0, 1, a2, false, 13});
    return lens;
}

// Thick-lens formulas (independent of the matrices of the code).
double singlet_efl()
{
    const double power = (kN - 1) * (1 / kR1 - 1 / kR2 + (kN - 1) * kT / (kN * kR1 * kR2));
    return 1 / power;
}
double singlet_bfd() { return singlet_efl() * (1 - (kN - 1) * kT / (kN * kR1)); }

// Image distance (from the vertex, + towards the image) of a point at distance u (signed the same
// way) through a spherical surface of radius R from index n1 into n2: n2 / v - n1 / u = (n2 - n1) / R.
double image_through_surface(double u, double n1, double n2, double R) { return n2 / ((n2 - n1) / R + n1 / u); }

TEST(AxialLimit, ParallelBeamFillsTheFirstRimAsWideAsTheStop)
{
    // Object at infinity (D = back focal distance): the marginal ray is parallel up to the lens,
    // so it has one height at the stop and at surface 1: the rim of 40 mm limits once the stop is
    // wider than 40 mm. Surface 2 sees the ray lower by 1 - t (n - 1) / (n R1) (refracted at
    // surface 1, then t through the glass), so its equal rim never limits first.
    const double D = singlet_bfd();
    for (double stop : {10.0, 30.0, 39.9, 40.1}) {
        const AxialLimit limit = axial_limit(stop_and_singlet(stop, 40, 40), D);
        ASSERT_TRUE(limit.valid);
        EXPECT_EQ(limit.surface, 0) << "stop " << stop << " (40.1: within the tolerance of 0.5 %)";
        EXPECT_EQ(limit.rim, 1);
        EXPECT_NEAR(limit.largest_stop_mm, 40, 1e-9);
    }
    for (double stop : {40.3, 60.0, 1e4})
        EXPECT_EQ(axial_limit(stop_and_singlet(stop, 40, 40), D).surface, 1) << "stop " << stop;
}

TEST(AxialLimit, ConvergingBeamInsideTheGlass)
{
    // A small rear rim (20 mm): the parallel marginal ray of height h at the stop has height
    // h (1 - t (n - 1) / (n R1)) at surface 2, so the stop limits up to 20 / that factor.
    const double factor = 1 - kT * (kN - 1) / (kN * kR1);
    const AxialLimit limit = axial_limit(stop_and_singlet(10, 40, 20), singlet_bfd());
    EXPECT_EQ(limit.surface, 0);
    EXPECT_EQ(limit.rim, 2);
    EXPECT_NEAR(limit.largest_stop_mm, 20 / factor, 1e-9);
    EXPECT_EQ(axial_limit(stop_and_singlet(25, 40, 20), singlet_bfd()).surface, 2);
}

TEST(AxialLimit, FiniteObjectDivergingBeam)
{
    // Object 200 mm in front of the stop: in air the marginal ray's height grows with the
    // distance from the object, so the 40 mm rim 10 mm behind the stop limits from a stop of
    // 40 * 200 / 210 on. The image distance D through the two surfaces, one at a time.
    const double object = 200;
    const double v1 = image_through_surface(-(object + kGap), 1, kN, kR1);
    const double D = image_through_surface(v1 - kT, kN, 1, kR2);
    ASSERT_GT(D, 0);
    const AxialLimit limit = axial_limit(stop_and_singlet(30, 40, 40), D);
    EXPECT_EQ(limit.surface, 0);
    EXPECT_NEAR(limit.largest_stop_mm, 40 * object / (object + kGap), 1e-9);
    EXPECT_EQ(axial_limit(stop_and_singlet(39, 40, 40), D).surface, 1);  // 39 > 38.1 * 1.005
}

TEST(AxialLimit, PupilsAndFNumberAreTheLimitingRimsImages)
{
    // Stop 60 mm wide: surface 1's rim (40 mm) limits the parallel beam. Nothing refracts in front
    // of it, so the entrance pupil is that rim itself (z = 10, 40 mm) and f_number = efl / 40; the
    // exit pupil is the rim imaged by surface 2 from inside the glass, t in front of it.
    const Prescription lens = stop_and_singlet(60, 40, 40);
    const ParaxialData p = paraxial_data(lens, 0, singlet_bfd());
    ASSERT_TRUE(p.valid);
    EXPECT_EQ(p.aperture_surface, 1);
    EXPECT_NEAR(p.aperture_z, kGap, 1e-12);
    EXPECT_EQ(p.aperture_mm, 40);
    EXPECT_NEAR(p.stop_mm, 60, 1e-12);  // the stop keeps its own diameter
    EXPECT_NEAR(p.entrance_pupil_z, kGap, 1e-9);
    EXPECT_NEAR(p.entrance_pupil_mm, 40, 1e-9);
    EXPECT_NEAR(p.efl_mm, singlet_efl(), 1e-9);
    EXPECT_NEAR(p.f_number, singlet_efl() / 40, 1e-9);
    const double v = image_through_surface(-kT, kN, 1, kR2);
    const double magnification = (kN * v) / (1 * -kT);
    EXPECT_NEAR(p.exit_pupil_z, kGap + kT + v, 1e-9);
    EXPECT_NEAR(p.exit_pupil_mm, 40 * std::fabs(magnification), 1e-9);
    EXPECT_NEAR(p.largest_stop_mm, 40, 1e-9);

    // Without an image distance the pupils stay the stop's (the stop is in front of everything:
    // the entrance pupil is the stop).
    const ParaxialData stop = paraxial_data(lens);
    EXPECT_EQ(stop.aperture_surface, 0);
    EXPECT_NEAR(stop.entrance_pupil_mm, 60, 1e-9);

    // The traced lens and its thick lens sample and assign microlenses from the same exit pupil
    // (optics frame: z = length - lens-frame z).
    for (bool exact : {true, false}) {
        const std::shared_ptr<const MainLens> made = make_prescription_lens(lens, 0, exact, singlet_bfd());
        ASSERT_TRUE(made);
        EXPECT_NEAR(made->exit_pupil_radius(), 20 * std::fabs(magnification), 1e-9);
        EXPECT_NEAR(made->exit_pupil_centre().z, (kGap + kT) - (kGap + kT + v), 1e-9);
    }
}

MainLensParams singlet_main(double stop, double f_number, double aperture)
{
    MainLensParams m;
    m.given = true;
    m.type = MainLensType::Prescription;
    m.has_prescription = true;
    m.prescription = stop_and_singlet(stop, 40, 40);
    m.has_distance = true;
    m.distance_mm = singlet_bfd();
    if (f_number > 0) {
        m.has_f_number = true;
        m.f_number = f_number;
    }
    if (aperture > 0) {
        m.has_aperture = true;
        m.aperture_mm = aperture;
    }
    return m;
}

TEST(AxialLimit, RefusesAStopTheLensCannotDeliver)
{
    // The stop is the entrance pupil here: f_number N asks for a stop of efl / N. The fastest the
    // lens reaches is efl / 40.
    const double efl = singlet_efl();
    EXPECT_EQ(check_main_lens(singlet_main(10, efl / 39, 0), 1), "");
    EXPECT_EQ(check_main_lens(singlet_main(10, efl / 40.1, 0), 1), "") << "within the tolerance";
    EXPECT_EQ(check_main_lens(singlet_main(10, 0, 39), 1), "");

    const std::string refused = check_main_lens(singlet_main(10, efl / 45, 0), 1);
    EXPECT_NE(refused.find("f_number " + format_number(efl / 45)), std::string::npos) << refused;
    EXPECT_NE(refused.find("surface 2 (scene line 12)"), std::string::npos) << refused;
    EXPECT_NE(refused.find("fastest f-number the lens reaches is " + format_rounded(efl / 40, true)), std::string::npos)
        << refused;
    EXPECT_NE(refused.find("at most 40 mm"), std::string::npos) << refused;
    EXPECT_EQ(refused, check_aperture_reach(singlet_main(10, efl / 45, 0), 1));

    const std::string wide = check_main_lens(singlet_main(10, 0, 50), 1);
    EXPECT_NE(wide.find("aperture 50"), std::string::npos) << wide;
    EXPECT_NE(wide.find("at most 40 mm"), std::string::npos) << wide;

    // The absurd stop of an f-number far beyond the lens (f/0.01 on a singlet).
    EXPECT_NE(check_main_lens(singlet_main(10, 0.01, 0), 1).find("fastest f-number"), std::string::npos);

    // The same f-number as a white image's.
    CameraParams camera;
    camera.main = singlet_main(10, 0, 0);
    camera.sensor.pixel_size_mm[0] = camera.sensor.pixel_size_mm[1] = 0.01;
    ASSERT_EQ(check_camera(camera), "");
    WhiteImageRequest white;
    white.given = true;
    white.f_numbers = {efl / 20, efl / 39};
    EXPECT_EQ(check_white_image(white, camera), "");
    white.f_numbers = {efl / 20, 0.01};
    const std::string refused_white = check_white_image(white, camera);
    EXPECT_NE(refused_white.find("white_image f_numbers 0.01"), std::string::npos) << refused_white;
    EXPECT_NE(refused_white.find("fastest f-number"), std::string::npos) << refused_white;
    EXPECT_EQ(refused_white, check_white_image_f_numbers(white, camera));
}

TEST(AxialLimit, StopWrittenWiderWarnsAndTheModelUsesTheRim)
{
    CameraParams camera;
    camera.main = singlet_main(60, 0, 0);  // as written, no f_number or aperture
    camera.sensor.pixel_size_mm[0] = camera.sensor.pixel_size_mm[1] = 0.01;
    ASSERT_EQ(check_camera(camera), "");
    const PlenopticCamera m = make_camera(camera);
    EXPECT_NEAR(m.f_number(), singlet_efl() / 40, 1e-9);
    EXPECT_NEAR(m.aperture_mm(), 60, 1e-12);  // the stop's diameter as written
    const double v = image_through_surface(-kT, kN, 1, kR2);
    EXPECT_NEAR(m.lens->exit_pupil_radius(), 20 * std::fabs(kN * v / -kT), 1e-9);
    const std::string warning = limiting_aperture_warning(m);
    EXPECT_EQ(warning.find("the stop (surface 1, scene line 11) is written 60 mm wide"), 0u) << warning;
    EXPECT_NE(warning.find("surface 2 (scene line 12)"), std::string::npos) << warning;
    EXPECT_NE(warning.find("f/" + format_rounded(singlet_efl() / 40, true)), std::string::npos) << warning;
    const std::vector<std::string> all = warnings(m);
    ASSERT_FALSE(all.empty());
    EXPECT_EQ(all[0], warning);

    camera.main = singlet_main(30, 0, 0);
    EXPECT_EQ(limiting_aperture_warning(make_camera(camera)), "");
}

TEST(AxialLimit, WhiteImageFNumbersListedTwiceAreRefused)
{
    WhiteImageRequest white;
    white.given = true;
    white.f_numbers = {2.8, 4, 2.8};
    const std::string message = repeated_white_f_number(white);
    EXPECT_NE(message.find("2.8 twice (values 1 and 3)"), std::string::npos) << message;
    EXPECT_NE(message.find(".white.f2.8.png"), std::string::npos) << message;
    white.f_numbers = {2.8, 4, 5.6};
    EXPECT_EQ(repeated_white_f_number(white), "");
}

} // namespace
} // namespace plenoptic
