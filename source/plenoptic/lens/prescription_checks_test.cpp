// SPDX-License-Identifier: AGPL-3.0-or-later
// What a prescription must be beyond its single rows: a lens file read as an editor may save it
// (a byte-order mark), said to be empty when it is, a huge radius read as flat, the iris's turn
// reduced by its symmetry, consecutive surfaces that cross, and a lens that diverges. Expected
// values come from closed forms (sags of spheres, the lensmaker's formula) and exact integer
// arithmetic, not from the code under test.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "plenoptic/lens/prescription.h"

namespace plenoptic {
namespace {

// A plano-convex singlet behind a stop: the stop, R = 100 (n = 1.5), then a rear surface whose
// radius is `rear`.
std::string plano_convex(const std::string& rear)
{
    return "0 10 0 10\n100 5 1.5 40\n" + rear + " 49 1 40\n";
}

// The number in `text` right before " mm" after `after` (the refusals print lengths so).
double number_after(const std::string& text, const std::string& after)
{
    const size_t at = text.find(after);
    if (at == std::string::npos)
        return NAN;
    return std::strtod(text.c_str() + at + after.size(), nullptr);
}

TEST(PrescriptionChecks, ALeadingByteOrderMarkIsSkipped)
{
    const std::string bom = "\xEF\xBB\xBF";
    const ParsedPrescription p = parse_lens_file(bom + "0 10 0 10\n100 5 1.5 40\n-100 49 1 40\n");
    ASSERT_FALSE(p.error.any()) << p.error.message;
    ASSERT_EQ(p.prescription.surfaces.size(), 3u);
    EXPECT_TRUE(p.prescription.surfaces[0].stop);
    EXPECT_EQ(p.prescription.surfaces[0].aperture_mm, 10);
    // Only a leading one: inside a row it is still not a number.
    const ParsedPrescription inside = parse_lens_file("0 10 0 10\n" + bom + "100 5 1.5 40\n-100 49 1 40\n");
    ASSERT_TRUE(inside.error.any());
    EXPECT_EQ(inside.error.line, 2);
}

TEST(PrescriptionChecks, AnEmptyFileOrOneWithoutRowsSaysSo)
{
    const ParsedPrescription empty = parse_lens_file("");
    ASSERT_TRUE(empty.error.any());
    EXPECT_NE(empty.error.message.find("the lens file is empty (0 bytes)"), std::string::npos) << empty.error.message;
    const ParsedPrescription comments = parse_lens_file("# radius thickness ior aperture\n\n");
    ASSERT_TRUE(comments.error.any());
    EXPECT_NE(comments.error.message.find("no surface row (only comments and blank lines)"), std::string::npos)
        << comments.error.message;
    const ParsedPrescription blank = parse_lens_file("\n  \n");
    ASSERT_TRUE(blank.error.any());
    EXPECT_NE(blank.error.message.find("no surface row (only blank lines)"), std::string::npos) << blank.error.message;
    // Each says what a lens file holds.
    EXPECT_NE(empty.error.message.find("one row per surface"), std::string::npos);
}

TEST(PrescriptionChecks, ARadiusBeyondTheLengthBoundIsFlat)
{
    // A plano-convex lens: f = R1 / (n - 1) = 200 mm whatever its thickness (Hecht 6.2 with
    // 1/R2 = 0), its rear focal point f (1 - (n - 1) t / (n R1)) behind the rear vertex.
    for (const char* rear : {"1e20", "-1e20", "1e200", "1e13"}) {
        const ParsedPrescription p = parse_lens_file(plano_convex(rear));
        ASSERT_FALSE(p.error.any()) << rear << ": " << p.error.message;
        const LensSurface& s = p.prescription.surfaces[2];
        EXPECT_EQ(s.radius_mm, 0) << rear;
        EXPECT_FALSE(s.stop) << rear;
        const ParaxialData par = paraxial_data(p.prescription);
        ASSERT_TRUE(par.valid) << rear;
        EXPECT_NEAR(par.efl_mm, 200, 1e-9) << rear;
        EXPECT_NEAR(par.bfd_mm, 200 * (1 - 0.5 * 5 / (1.5 * 100)), 1e-9) << rear;
        // The lens passes light (a radius of 1e20 mm used to block every ray): a paraxial ray
        // crosses the axis at the rear focal point.
        const Traced out = trace_from_object(p.prescription, LensRay{Vec3{0, 1e-3, -1}, Vec3{0, 0, 1}});
        ASSERT_EQ(out.result, TraceResult::Passed) << rear;
        const double crossing = out.ray.origin.z - out.ray.origin.y / out.ray.dir.y * out.ray.dir.z;
        EXPECT_NEAR(crossing, par.rear_focal_z, 1e-5) << rear;
    }
    // Within the bound a radius is a sphere.
    const ParsedPrescription near = parse_lens_file(plano_convex("-1e12"));
    ASSERT_FALSE(near.error.any()) << near.error.message;
    EXPECT_EQ(near.prescription.surfaces[2].radius_mm, -1e12);
    EXPECT_EQ(flat_radius(1e12), 1e12);
    EXPECT_EQ(flat_radius(-1.0000001e12), 0);
    // A prescription built without a parser is refused there, naming the bound; so are the other
    // lengths of a lens file.
    Prescription built = near.prescription;
    built.surfaces[2].radius_mm = 1e20;
    const PrescriptionError error = check_prescription(built);
    ASSERT_TRUE(error.any());
    EXPECT_NE(error.message.find("1e+20 mm"), std::string::npos) << error.message;
    EXPECT_NE(error.message.find("1e+12 mm"), std::string::npos) << error.message;
    EXPECT_EQ(error.line, 3);
    const ParsedPrescription thick = parse_lens_file("0 10 0 10\n100 2e12 1.5 40\n-100 49 1 40\n");
    ASSERT_TRUE(thick.error.any());
    EXPECT_NE(thick.error.message.find("thickness 2e+12 mm exceeds 1e+12 mm"), std::string::npos) << thick.error.message;
    EXPECT_EQ(thick.error.line, 2);
    const ParsedPrescription wide = parse_lens_file("0 10 0 3e12\n0.5e300 5 1.5 40\n-100 49 1 40\n");
    ASSERT_TRUE(wide.error.any());
    EXPECT_NE(wide.error.message.find("aperture diameter 3e+12 mm exceeds 1e+12 mm"), std::string::npos) << wide.error.message;
}

// x mod p for a double x that holds an integer, by exact integer arithmetic on its mantissa and
// power of two (x = m 2^k).
std::int64_t integer_mod(double x, std::int64_t p)
{
    int exponent = 0;
    const double fraction = std::frexp(x, &exponent);
    std::int64_t m = std::int64_t(std::ldexp(fraction, 53)) % p;
    for (int k = 0; k < exponent - 53; ++k)
        m = (2 * m) % p;
    return m;
}

TEST(PrescriptionChecks, BladeRotationIsReducedByTheIrisSymmetry)
{
    EXPECT_EQ(reduced_blade_rotation(15, 6), 15);
    EXPECT_EQ(reduced_blade_rotation(75, 6), 15);
    EXPECT_EQ(reduced_blade_rotation(-30, 6), 30);
    EXPECT_EQ(reduced_blade_rotation(370, 0), 10);
    EXPECT_EQ(reduced_blade_rotation(-10, 0), 350);
    // 1e300 holds an integer; its remainder modulo 60 (and 360) is an exact integer.
    EXPECT_EQ(reduced_blade_rotation(1e300, 6), double(integer_mod(1e300, 60)));
    EXPECT_EQ(reduced_blade_rotation(1e300, 0), double(integer_mod(1e300, 360)));
    EXPECT_EQ(reduced_blade_rotation(-1e300, 8), double((45 - integer_mod(1e300, 45)) % 45));
    for (int blades : {3, 7, 11, 1000}) {
        const double r = reduced_blade_rotation(1e300, blades);
        EXPECT_GE(r, 0) << blades;
        EXPECT_LT(r, 360.0 / blades) << blades;
    }

    // The iris turned by 45 * 2^60 degrees, a whole multiple of 60, is the hexagon turned by 0:
    // its sides' midpoints 5 cos 30 = 4.33 mm from the axis at 0, 60, ... 300 degrees. (The
    // unreduced angle swamped the 60 degrees between the blades: one blade, a half plane.)
    Prescription lens;
    lens.surfaces.push_back(LensSurface{0, 10, 0, 10, true, 1});
    lens.surfaces.push_back(LensSurface{100, 5, 1.5, 40, false, 2});
    lens.surfaces.push_back(LensSurface{-100, 0, 1, 40, false, 3});
    lens.blades = 6;
    lens.blade_rotation_deg = std::ldexp(45.0, 60);
    EXPECT_EQ(integer_mod(lens.blade_rotation_deg, 60), 0);
    for (int k = 0; k < 6; ++k) {
        const double a = k * kPi / 3;
        EXPECT_EQ(trace_from_object(lens, LensRay{Vec3{4.2 * std::cos(a), 4.2 * std::sin(a), -1}, Vec3{0, 0, 1}}).result,
                  TraceResult::Passed) << k;
        EXPECT_EQ(trace_from_object(lens, LensRay{Vec3{4.45 * std::cos(a), 4.45 * std::sin(a), -1}, Vec3{0, 0, 1}}).result,
                  TraceResult::Stop) << k;
        // The corners, 5 mm out at 30, 90, ... degrees.
        const double corner = a + kPi / 6;
        EXPECT_EQ(trace_from_object(lens, LensRay{Vec3{4.9 * std::cos(corner), 4.9 * std::sin(corner), -1}, Vec3{0, 0, 1}}).result,
                  TraceResult::Passed) << k;
    }
}

TEST(PrescriptionChecks, ConsecutiveSurfacesThatCrossAreRefused)
{
    // A biconvex element R1 = 20, R2 = -20, 30 mm across, 2 mm thick at the centre: each sag at
    // height h is 20 - sqrt(400 - h^2), so the surfaces meet where that is 1 mm: h = sqrt(39).
    const ParsedPrescription thin = parse_lens_file("0 2 0 10\n20 2 1.5 30\n-20 40 1 30\n");
    ASSERT_TRUE(thin.error.any());
    const std::string& message = thin.error.message;
    EXPECT_EQ(thin.error.line, 2);
    EXPECT_NE(message.find("surface 2 (line 2) and surface 3 (line 3) cross"), std::string::npos) << message;
    EXPECT_NEAR(number_after(message, "they meet "), std::sqrt(39.0), 1e-4) << message;
    // At the rim (15 mm) the rear surface lies 2 (20 - sqrt(175)) - 2 mm in front of the front one.
    EXPECT_NEAR(number_after(message, "surface 3 lies "), 2 * (20 - std::sqrt(175.0)) - 2, 1e-4) << message;
    // Thick enough, or touching at the rim (a knife edge), it is a lens.
    EXPECT_FALSE(parse_lens_file("0 2 0 10\n20 14 1.5 30\n-20 40 1 30\n").error.any());
    Prescription edge = parse_lens_file("0 2 0 10\n20 14 1.5 30\n-20 40 1 30\n").prescription;
    edge.surfaces[1].thickness_mm = 2 * (20 - std::sqrt(175.0));
    EXPECT_FALSE(check_prescription(edge).any()) << check_prescription(edge).message;
    // The stop counts as a flat surface: a concave surface right behind it bulges through it
    // within the stop's 10 mm (sag at 5 mm: -(20 - sqrt(375))).
    const ParsedPrescription stop = parse_lens_file("20 10 1.5 30\n-60 0.2 1 30\n0 0 0 10\n-20 3 1.5 30\n40 40 1 30\n");
    ASSERT_TRUE(stop.error.any());
    EXPECT_NE(stop.error.message.find("the stop (surface 3, line 3) and surface 4 (line 4) cross"), std::string::npos)
        << stop.error.message;
    EXPECT_NEAR(number_after(stop.error.message, "surface 4 lies "), 20 - std::sqrt(375.0), 1e-6) << stop.error.message;
    EXPECT_NEAR(number_after(stop.error.message, "they meet "), 0, 1e-9) << stop.error.message;
}

TEST(PrescriptionChecks, ADivergingLensIsRefusedWithItsFocalLength)
{
    // A biconcave singlet R1 = -50, R2 = 50, n = 1.5, t = 2 behind a stop: the lensmaker's
    // formula 1/f = (n - 1) [1/R1 - 1/R2 + (n - 1) t / (n R1 R2)].
    const double n = 1.5, R1 = -50, R2 = 50, t = 2;
    const double f = 1 / ((n - 1) * (1 / R1 - 1 / R2 + (n - 1) * t / (n * R1 * R2)));
    ASSERT_LT(f, 0);
    const ParsedPrescription p = parse_lens_file("0 3 0 10\n-50 2 1.5 30\n50 40 1 30\n");
    ASSERT_TRUE(p.error.any());
    EXPECT_NE(p.error.message.find("negative focal length"), std::string::npos) << p.error.message;
    EXPECT_NE(p.error.message.find("positive focal length"), std::string::npos) << p.error.message;
    EXPECT_NEAR(number_after(p.error.message, "effective focal length is "), f, 1e-3) << p.error.message;
    // The same element the other way round converges and is a lens.
    EXPECT_FALSE(parse_lens_file("0 3 0 10\n50 8 1.5 30\n-50 40 1 30\n").error.any());
}

} // namespace
} // namespace plenoptic
