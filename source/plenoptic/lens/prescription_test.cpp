// SPDX-License-Identifier: AGPL-3.0-or-later
// The prescription core: reading pbrt lens files, the refusals, first-order data
// against the textbook formulas of a thick lens, and the exact trace against the exact
// (trigonometric) refraction at one spherical surface.

#include <gtest/gtest.h>

#include <cmath>

#include "plenoptic/lens/prescription.h"

namespace plenoptic {
namespace {

// A biconvex singlet (R1 = 100, R2 = -100, n = 1.5, centre thickness t) behind a stop 10 mm in
// front of it.
Prescription singlet(double t, double stop_mm = 10)
{
    Prescription lens;
    lens.surfaces.push_back(LensSurface{0, 10, 0, stop_mm, true, 1});
    lens.surfaces.push_back(LensSurface{100, t, 1.5, 40, false, 2});
    lens.surfaces.push_back(LensSurface{-100, 0, 1, 40, false, 3});
    return lens;
}

TEST(Prescription, ReadsPbrtLensFiles)
{
    const ParsedPrescription p = parse_lens_file(
        "# a singlet behind a stop\n"
        "#  radius  thickness  ior  aperture\n"
        "   0       10         0    10      # the stop\n"
        "\n"
        "   100     5          1.5  40\n"
        "  -100     49.0       1    40\n");
    ASSERT_FALSE(p.error.any()) << p.error.message;
    ASSERT_EQ(p.prescription.surfaces.size(), 3u);
    EXPECT_TRUE(p.prescription.surfaces[0].stop);
    EXPECT_EQ(p.prescription.surfaces[1].radius_mm, 100);
    EXPECT_EQ(p.prescription.surfaces[1].ior, 1.5);
    EXPECT_EQ(p.prescription.surfaces[2].radius_mm, -100);
    EXPECT_EQ(p.prescription.surfaces[2].thickness_mm, 49);
    EXPECT_EQ(p.prescription.surfaces[2].line, 6);
    const std::vector<double> z = vertex_positions(p.prescription);
    EXPECT_EQ(z[1], 10);
    EXPECT_EQ(z[2], 15);
}

struct Refusal {
    const char* text;
    int line;
    const char* says;
};

TEST(Prescription, RefusesWhatTheIssueNames)
{
    const Refusal cases[] = {
        {"# nothing\n", 0, "no surface row"},
        {"100 5 1.5 40\n-100 40 1 40\n", 0, "no aperture stop"},
        {"0 1 0 10\n100 5 1.5 40\n0 1 0 10\n-100 40 1 40\n", 3, "two aperture stops"},
        {"0 1 0 10\n100 5 1.5 0\n-100 40 1 40\n", 2, "aperture diameter must be > 0"},
        {"0 1 0 -3\n100 5 1.5 40\n-100 40 1 40\n", 1, "aperture diameter must be > 0"},
        {"0 1 0 10\n10 5 1.5 40\n-100 40 1 40\n", 2, "exceeds the surface's sphere"},
        {"0 1 0 10\n100 5 1.5 40\n-100 40 1.5 40\n", 3, "open into air"},
        {"0 1 0 10\n100 5 0.5 40\n-100 40 1 40\n", 2, "index of refraction must be >= 1"},
        {"0 1 0 10\n100 -5 1.5 40\n-100 40 1 40\n", 2, "thickness must be >= 0"},
        {"0 1 0 10\n100 5 1.5\n", 2, "four numbers"},
        {"0 1 0 10\n100 5 1.5 forty\n", 2, "'forty' is not a finite number"},
        {"0 1 0 10\n100 5 1.5 nan\n", 2, "not a finite number"},
        {"0 1 0 10\n100 5 1.5 1e999\n", 2, "not a finite number"},
    };
    for (const Refusal& c : cases) {
        const ParsedPrescription p = parse_lens_file(c.text);
        EXPECT_TRUE(p.error.any()) << c.text;
        EXPECT_NE(p.error.message.find(c.says), std::string::npos) << c.text << " gave: " << p.error.message;
        EXPECT_EQ(p.error.line, c.line) << c.text << " gave: " << p.error.message;
    }
}

TEST(Prescription, ParaxialDataOfAThickLensMatchesTheLensmakerFormulas)
{
    // Independent closed forms (Hecht, Optics, 6.2): 1/f = (n-1) [1/R1 - 1/R2 + (n-1) t / (n R1 R2)];
    // back focal distance f (1 - (n-1) t / (n R1)); rear principal plane -f (n-1) t / (n R2)...
    // measured from the rear vertex: h2 = -f (n-1) t / (n R1); front: h1 = -f (n-1) t / (n R2).
    const double n = 1.5, R1 = 100, R2 = -100;
    for (double t : {0.0, 5.0, 20.0}) {
        const ParaxialData p = paraxial_data(singlet(t));
        ASSERT_TRUE(p.valid);
        const double f = 1 / ((n - 1) * (1 / R1 - 1 / R2 + (n - 1) * t / (n * R1 * R2)));
        EXPECT_NEAR(p.efl_mm, f, 1e-9 * f) << "t = " << t;
        EXPECT_NEAR(p.bfd_mm, f * (1 - (n - 1) * t / (n * R1)), 1e-9 * f) << "t = " << t;
        const double h2 = -f * (n - 1) * t / (n * R1);  // rear principal plane from the rear vertex
        const double h1 = -f * (n - 1) * t / (n * R2);  // front principal plane from the front vertex
        EXPECT_NEAR(p.rear_principal_z, 10 + t + h2, 1e-9 * f) << "t = " << t;
        EXPECT_NEAR(p.front_principal_z, 10 + h1, 1e-9 * f) << "t = " << t;
        EXPECT_NEAR(p.rear_focal_z - p.rear_principal_z, f, 1e-9 * f);
        EXPECT_NEAR(p.front_principal_z - p.front_focal_z, f, 1e-9 * f);
    }
}

TEST(Prescription, PupilsOfAStopInFrontOfAThinLens)
{
    // The stop is the entrance pupil (nothing in front of it). The exit pupil is the stop's image
    // through the lens: a thin lens of f = 100 at 10 mm from the stop images it at
    // 1/s' = 1/f - 1/s with s = 10 in front: s' = 1 / (1/100 - 1/10) = -11.11 mm (virtual, in front
    // of the lens), magnified s'/(-s) = 1.111.
    const ParaxialData p = paraxial_data(singlet(0, 8));
    ASSERT_TRUE(p.valid);
    EXPECT_DOUBLE_EQ(p.entrance_pupil_z, 0);
    EXPECT_DOUBLE_EQ(p.entrance_pupil_mm, 8);
    const double s_image = 1 / (1.0 / 100 - 1.0 / 10);
    EXPECT_NEAR(p.exit_pupil_z, 10 + s_image, 1e-9);
    EXPECT_NEAR(p.exit_pupil_mm, 8 * std::fabs(s_image / -10), 1e-9);
    EXPECT_NEAR(p.f_number, 100.0 / 8, 1e-9);
    // The stop that gives f/4: an entrance pupil of 25 mm.
    const double stop = stop_diameter_for_f_number(singlet(0, 8), 4);
    EXPECT_NEAR(stop, 25, 1e-9);
    EXPECT_NEAR(paraxial_data(singlet(0, 8), stop).f_number, 4, 1e-12);
}

TEST(Prescription, ParaxialImageDistanceIsTheThinLensConjugate)
{
    const Prescription lens = singlet(0);
    // 1/s' = 1/f - 1/s for objects 10 m, 1 m and 200 mm away, and at infinity.
    for (double s : {10000.0, 1000.0, 200.0}) {
        const ImageDistance image = paraxial_image_distance(lens, s - 10);  // from the front vertex (the stop)
        ASSERT_TRUE(image.real);
        EXPECT_NEAR(image.mm, 1 / (1.0 / 100 - 1 / s), 1e-9);
    }
    EXPECT_NEAR(paraxial_image_distance(lens, INFINITY).mm, 100, 1e-9);
    // An object inside the focal length images virtually: no sensor position focuses it.
    EXPECT_FALSE(paraxial_image_distance(lens, 50).real);
}

TEST(Prescription, OneSphericalSurfaceHasTheExactLongitudinalAberration)
{
    // A parallel ray at height h meets a sphere of radius R (centre C on the axis) at incidence i,
    // sin i = h / R, refracts to r, sin r = sin i / n, and crosses the axis at
    // L' = R + R sin r / sin(i - r) from the vertex (law of sines in the triangle C, hit, crossing).
    // Paraxially L' = n R / (n - 1); the difference is the longitudinal spherical aberration.
    const double R = 50, n = 1.6;
    Prescription lens;
    lens.surfaces.push_back(LensSurface{0, 0, 0, 80, true, 0});
    lens.surfaces.push_back(LensSurface{R, 200, n, 80, false, 0});
    for (double h : {0.01, 5.0, 10.0, 20.0, 30.0}) {
        const Traced out = trace_from_object(lens, LensRay{Vec3{0, h, -10}, Vec3{0, 0, 1}});
        ASSERT_EQ(out.result, TraceResult::Passed) << h;
        const double along = -out.ray.origin.y / out.ray.dir.y;
        const double crossing = out.ray.origin.z + along * out.ray.dir.z;
        const double i = std::asin(h / R), r = std::asin(std::sin(i) / n);
        const double exact = R + R * std::sin(r) / std::sin(i - r);
        EXPECT_NEAR(crossing, exact, 1e-9 * exact) << "h = " << h;
        if (h > 1) {
            EXPECT_LT(crossing, n * R / (n - 1) - 1e-3) << "h = " << h;  // marginal rays focus short
        }
    }
}

TEST(Prescription, ParaxialRaysOfTheTraceMeetAtTheRearFocus)
{
    const Prescription lens = singlet(5, 10);
    const ParaxialData p = paraxial_data(lens);
    const Traced out = trace_from_object(lens, LensRay{Vec3{0, 1e-3, -10}, Vec3{0, 0, 1}});
    ASSERT_EQ(out.result, TraceResult::Passed);
    const double crossing = out.ray.origin.z - out.ray.origin.y / out.ray.dir.y * out.ray.dir.z;
    EXPECT_NEAR(crossing, p.rear_focal_z, 1e-6);
}

TEST(Prescription, TracingBackwardsRetracesTheRay)
{
    const Prescription lens = singlet(5, 10);
    for (double h : {0.0, 1.0, 3.0, 4.5}) {
        const LensRay in{Vec3{0.3, h, -20}, normalized(Vec3{0.01, -0.02, 1})};
        const Traced forward = trace_from_object(lens, in);
        ASSERT_EQ(forward.result, TraceResult::Passed) << h;
        const LensRay back_in{forward.ray.origin + 30.0 * forward.ray.dir, -forward.ray.dir};
        const Traced back = trace_from_image(lens, back_in);
        ASSERT_EQ(back.result, TraceResult::Passed) << h;
        // The returning ray runs along the incoming line, reversed.
        EXPECT_NEAR(dot(back.ray.dir, in.dir), -1, 1e-12);
        const Vec3 d = back.ray.origin - in.origin;
        const Vec3 off = d - dot(d, in.dir) * in.dir;
        EXPECT_LT(length(off), 1e-9) << h;
    }
}

TEST(Prescription, ApertureStopAndIrisBlock)
{
    Prescription lens = singlet(5, 10);
    EXPECT_EQ(trace_from_object(lens, LensRay{Vec3{0, 4.9, -1}, Vec3{0, 0, 1}}).result, TraceResult::Passed);
    const Traced blocked = trace_from_object(lens, LensRay{Vec3{0, 5.1, -1}, Vec3{0, 0, 1}});
    EXPECT_EQ(blocked.result, TraceResult::Stop);
    EXPECT_EQ(blocked.surface, 0);
    // A hexagonal iris with corners on the 5 mm circle: a side's midpoint lies at 5 cos 30 deg.
    lens.blades = 6;
    lens.blade_rotation_deg = 0;  // one side's normal along +x
    EXPECT_EQ(trace_from_object(lens, LensRay{Vec3{4.2, 0, -1}, Vec3{0, 0, 1}}).result, TraceResult::Passed);
    EXPECT_EQ(trace_from_object(lens, LensRay{Vec3{4.4, 0, -1}, Vec3{0, 0, 1}}).result, TraceResult::Stop);
    const double corner = 30 * kPi / 180;  // a corner between the sides at 0 and 60 degrees
    EXPECT_EQ(trace_from_object(lens, LensRay{Vec3{4.9 * std::cos(corner), 4.9 * std::sin(corner), -1}, Vec3{0, 0, 1}})
                  .result,
              TraceResult::Passed);
    // A clear aperture: a ray far off the axis misses the glass's 40 mm rim.
    Prescription wide = singlet(5, 100);
    const Traced rim = trace_from_object(wide, LensRay{Vec3{0, 21, -1}, Vec3{0, 0, 1}});
    EXPECT_EQ(rim.result, TraceResult::ClearAperture);
    EXPECT_EQ(rim.surface, 1);
}

TEST(Prescription, TotalInternalReflectionBlocks)
{
    // Inside glass of index 1.5 the critical angle is asin(1/1.5) = 41.8 deg: a ray meeting the
    // (almost flat) front surface from inside at 45 degrees is reflected, at 40 degrees it leaves.
    Prescription lens;
    lens.surfaces.push_back(LensSurface{0, 0, 0, 100, true, 0});
    lens.surfaces.push_back(LensSurface{1e6, 10, 1.5, 100, false, 0});
    lens.surfaces.push_back(LensSurface{-1e6, 0, 1, 100, false, 0});
    // The ray starts inside the glass (the rear surface removed) and travels towards the front.
    const auto at = [&](double degrees) {
        const double a = degrees * kPi / 180;
        Prescription glass = lens;
        glass.surfaces.erase(glass.surfaces.begin() + 2);  // the ray starts inside the glass
        glass.surfaces[1].thickness_mm = 10;
        return trace_from_image(glass, LensRay{Vec3{0, 0, 5}, Vec3{0, std::sin(a), -std::cos(a)}}).result;
    };
    EXPECT_EQ(at(40), TraceResult::Passed);
    EXPECT_EQ(at(45), TraceResult::TotalInternalReflection);
}

} // namespace
} // namespace plenoptic
