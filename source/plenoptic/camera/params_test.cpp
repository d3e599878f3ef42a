// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the parse-time checks: every refusal names its keyword, value and range.

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "plenoptic/camera/params.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;
using test::thin_lens_camera;

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

struct ValueCase {
    std::string message;
    const char* keyword;
    const char* value;
};

TEST(Params, PerValueRefusalsNameKeywordValueAndRange)
{
    const ValueCase cases[] = {
        {check_positive_length("pitch", -0.5), "pitch", "-0.5"},
        {check_positive_length("pitch", 0), "pitch", "got 0"},
        {check_positive_length("focal_length", kNaN), "focal_length", "nan"},
        {check_positive_length("distance", kInf), "distance", "inf"},
        {check_positive_length("pixel_size", -1e-300), "pixel_size", "-1e-300"},
        {check_f_number(0), "f_number", "got 0"},
        {check_f_number(-2), "f_number", "-2"},
        {check_f_number(kNaN), "f_number", "nan"},
        {check_mm_per_unit(0), "mm_per_unit", "got 0"},
        {check_mm_per_unit(-kInf), "mm_per_unit", "-inf"},
        {check_focus_distance(-2.5), "focus_distance", "-2.5"},
        {check_angle("rotate", kNaN), "rotate", "nan"},
        {check_translation("translate", kInf), "translate", "inf"},
        {check_translation("offset", kNaN), "offset", "nan"},
        {check_translation("translate", 8.0298913057934345e+283), "translate", "8.029891305793435e+283"},
        {check_translation("offset", -2e12), "offset", "-2000000000000"},
        {check_samples("samples", 0), "samples", "got 0"},
        {check_samples("samples", 2.5), "samples", "2.5"},
        {check_samples("samples", 1e12), "samples", "1000000000000"},
        {check_samples("samples", kNaN), "samples", "nan"},
        {check_confidence(1), "confidence", "got 1"},
        {check_confidence(0), "confidence", "got 0"},
        {check_confidence(1.5), "confidence", "1.5"},
        {check_variance(0), "variance", "got 0"},
        {check_variance(-1), "variance", "-1"},
        {check_finite("anything", kNaN), "anything", "nan"},
    };
    for (const ValueCase& c : cases) {
        EXPECT_FALSE(c.message.empty()) << "expected a refusal for " << c.keyword << " = " << c.value;
        EXPECT_TRUE(contains(c.message, c.keyword)) << c.message;
        EXPECT_TRUE(contains(c.message, c.value)) << c.message;
    }
    // The valid range is stated.
    EXPECT_TRUE(contains(check_positive_length("pitch", -0.5), "> 0")) << check_positive_length("pitch", -0.5);
    EXPECT_EQ(check_positive_length("pitch", -0.5), "pitch must be a positive length in mm (> 0), got -0.5");
    EXPECT_TRUE(contains(check_samples("samples", 0), "1 to 1000000")) << check_samples("samples", 0);
    EXPECT_TRUE(contains(check_confidence(2), "0 < confidence < 1")) << check_confidence(2);
}

TEST(Params, PerValueChecksAcceptValidValues)
{
    EXPECT_EQ(check_positive_length("pitch", 0.5), "");
    EXPECT_EQ(check_positive_length("pitch", kMinLengthMm), "");
    EXPECT_EQ(check_positive_length("pitch", kMaxLengthMm), "");
    EXPECT_TRUE(contains(check_positive_length("pitch", 1e-300), "1e-12 to 1000000000000 mm")) << check_positive_length("pitch", 1e-300);
    EXPECT_TRUE(contains(check_positive_length("pitch", 1e13), "1e-12 to 1000000000000 mm")) << check_positive_length("pitch", 1e13);
    EXPECT_EQ(check_f_number(4), "");
    EXPECT_EQ(check_mm_per_unit(1000), "");
    EXPECT_EQ(check_focus_distance(2.5), "");
    EXPECT_EQ(check_angle("rotate", -720), "");
    EXPECT_EQ(check_translation("translate", -3), "");
    EXPECT_EQ(check_translation("offset", kMaxLengthMm), "");
    EXPECT_EQ(check_samples("samples", 1), "");
    EXPECT_EQ(check_samples("samples", 1000000), "");
    EXPECT_EQ(check_confidence(0.9), "");
    EXPECT_EQ(check_variance(1.0 / 128), "");
}

TEST(Params, FormatNumberIsShortestRoundTrip)
{
    EXPECT_EQ(format_number(0.5), "0.5");
    EXPECT_EQ(format_number(0.1), "0.1");
    EXPECT_EQ(format_number(-1e-300), "-1e-300");
    EXPECT_EQ(format_number(0.1 + 0.2), "0.30000000000000004");
    EXPECT_EQ(format_number(kNaN), "nan");
    EXPECT_EQ(format_number(-kInf), "-inf");
}

MainLensParams thin_main()
{
    MainLensParams m;
    m.given = true;
    m.type = MainLensType::ThinLens;
    m.has_focal_length = true;
    m.focal_length_mm = 50;
    m.has_f_number = true;
    m.f_number = 4;
    m.has_focus_distance = true;
    m.focus_distance_units = 2.5;
    return m;
}

TEST(Params, MainLensCrossFieldRefusals)
{
    EXPECT_EQ(check_main_lens(thin_main(), 1000), "");

    MainLensParams m = thin_main();
    m.has_aperture = true;
    m.aperture_mm = 12.5;
    std::string message = check_main_lens(m, 1000);
    EXPECT_TRUE(contains(message, "f_number") && contains(message, "aperture") && contains(message, "not both"))
        << message;

    m = thin_main();
    m.has_f_number = false;
    message = check_main_lens(m, 1000);
    EXPECT_TRUE(contains(message, "f_number or aperture")) << message;

    m = thin_main();
    m.has_distance = true;
    m.distance_mm = 52;
    message = check_main_lens(m, 1000);
    EXPECT_TRUE(contains(message, "focus_distance or distance, not both")) << message;

    m = thin_main();
    m.has_focus_distance = false;
    message = check_main_lens(m, 1000);
    EXPECT_TRUE(contains(message, "focus_distance") && contains(message, "distance")) << message;

    m = thin_main();
    m.has_focal_length = false;
    message = check_main_lens(m, 1000);
    EXPECT_TRUE(contains(message, "focal_length")) << message;

    // Focus at and inside the focal length: 0.05 units = 50 mm = F.
    for (double focus : {0.05, 0.04, 1e-9}) {
        m = thin_main();
        m.focus_distance_units = focus;
        message = check_main_lens(m, 1000);
        EXPECT_TRUE(contains(message, "focus_distance") && contains(message, "focal length") &&
                    contains(message, format_number(focus)))
            << focus << ": " << message;
    }
    m = thin_main();
    m.focus_distance_units = 0.050001;
    EXPECT_EQ(check_main_lens(m, 1000), "");
    // mm_per_unit takes part: 1 unit = 1 mm puts 2.5 inside F = 50 mm.
    m = thin_main();
    message = check_main_lens(m, 1);
    EXPECT_TRUE(contains(message, "focus_distance")) << message;

    m = MainLensParams();
    m.given = true;
    message = check_main_lens(m, 1000);
    EXPECT_TRUE(contains(message, "thin_lens, pinhole, or a real lens")) << message;
}

// F / N must give an aperture in the range a given aperture has: a fuzzed f_number of 2e-230
// passed the old finite-and-positive check, and under irradiance the aperture's area overflowed
// to a NaN pixel.
TEST(Params, ThinLensFNumberGivesAnApertureInRange)
{
    for (double n : {2.0611676062710827e-230, 50 / (2 * kMaxLengthMm), 50 / (0.5 * kMinLengthMm), 1e300}) {
        MainLensParams m = thin_main();
        m.f_number = n;
        const std::string message = check_main_lens(m, 1000);
        EXPECT_TRUE(contains(message, "f_number " + format_number(n)) && contains(message, "outside"))
            << n << ": " << message;
    }
    for (double n : {50 / kMaxLengthMm, 50 / kMinLengthMm, 1.4, 64.0}) {
        MainLensParams m = thin_main();
        m.f_number = n;
        EXPECT_EQ(check_main_lens(m, 1000), "") << n;
    }
}

TEST(Params, PinholeMainLensTakesDistanceOnly)
{
    MainLensParams m;
    m.given = true;
    m.type = MainLensType::Pinhole;
    m.has_distance = true;
    m.distance_mm = 50;
    EXPECT_EQ(check_main_lens(m, 1000), "");

    MainLensParams bad = m;
    bad.has_focal_length = true;
    bad.focal_length_mm = 50;
    EXPECT_TRUE(contains(check_main_lens(bad, 1000), "focal_length")) << check_main_lens(bad, 1000);
    bad = m;
    bad.has_f_number = true;
    bad.f_number = 4;
    EXPECT_TRUE(contains(check_main_lens(bad, 1000), "f_number")) << check_main_lens(bad, 1000);
    bad = m;
    bad.has_aperture = true;
    bad.aperture_mm = 4;
    EXPECT_TRUE(contains(check_main_lens(bad, 1000), "aperture")) << check_main_lens(bad, 1000);
    bad = m;
    bad.has_distance = false;
    bad.has_focus_distance = true;
    bad.focus_distance_units = 3;
    EXPECT_TRUE(contains(check_main_lens(bad, 1000), "focus_distance")) << check_main_lens(bad, 1000);
    bad = m;
    bad.has_distance = false;
    EXPECT_TRUE(contains(check_main_lens(bad, 1000), "needs distance")) << check_main_lens(bad, 1000);
}

TEST(Params, ArrayCrossFieldRefusals)
{
    CameraParams camera = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52);
    EXPECT_EQ(check_array(camera.array), "");

    ArrayParams a = camera.array;
    a.grid = GridType::Rectangular;
    a.lens = MicrolensType::ThinLens;
    a.focal_length_count = 3;
    a.focal_lengths_mm[0] = 1.9;
    a.focal_lengths_mm[1] = 2.0;
    a.focal_lengths_mm[2] = 2.1;
    std::string message = check_array(a);
    EXPECT_TRUE(contains(message, "focal_lengths") && contains(message, "hexagonal")) << message;
    a.grid = GridType::Hexagonal;
    EXPECT_EQ(check_array(a), "");
    a.focal_lengths_mm[1] = -2;
    message = check_array(a);
    EXPECT_TRUE(contains(message, "focal_lengths") && contains(message, "-2")) << message;

    a = camera.array;
    a.has_pitch = false;
    EXPECT_TRUE(contains(check_array(a), "pitch")) << check_array(a);
    a = camera.array;
    a.pitch_mm = -0.5;
    EXPECT_TRUE(contains(check_array(a), "pitch") && contains(check_array(a), "-0.5")) << check_array(a);
    a = camera.array;
    a.has_lens = false;
    EXPECT_TRUE(contains(check_array(a), "pinhole")) << check_array(a);
    a = camera.array;
    a.has_distance = false;
    EXPECT_TRUE(contains(check_array(a), "distance")) << check_array(a);
    a = camera.array;
    a.grid = GridType::None;
    EXPECT_TRUE(contains(check_array(a), "rectangular or hexagonal")) << check_array(a);
    a = camera.array;
    a.rotate_deg[1] = kNaN;
    EXPECT_TRUE(contains(check_array(a), "rotate")) << check_array(a);
    a = camera.array;
    a.translate_mm[2] = kInf;
    EXPECT_TRUE(contains(check_array(a), "translate")) << check_array(a);
    a = camera.array;
    a.lens = MicrolensType::Pinhole;  // with focal_length_count 1
    EXPECT_TRUE(contains(check_array(a), "not both")) << check_array(a);
}

TEST(Params, SensorAndSamplingRefusals)
{
    SensorParams s;
    EXPECT_EQ(check_sensor(s), "");
    s.pixel_size_mm[1] = 0;
    EXPECT_TRUE(contains(check_sensor(s), "pixel_size")) << check_sensor(s);
    s = SensorParams();
    s.offset_mm[0] = kNaN;
    EXPECT_TRUE(contains(check_sensor(s), "offset")) << check_sensor(s);

    SamplingParams p;
    EXPECT_EQ(check_sampling(p), "");
    p.samples = -1;
    EXPECT_TRUE(contains(check_sampling(p), "samples")) << check_sampling(p);
    // 0 in the struct means `samples` was omitted; typed in a scene, 0 is refused.
    p.samples = kSamplesOmitted;
    EXPECT_EQ(check_sampling(p), "");
    EXPECT_TRUE(contains(check_samples("samples", 0), "samples")) << check_samples("samples", 0);
    p = SamplingParams();
    p.adaptive = true;
    p.samples_min = 16;
    p.samples_max = 4;
    std::string message = check_sampling(p);
    EXPECT_TRUE(contains(message, "samples") && contains(message, "16") && contains(message, "4")) << message;
    p.samples_max = 64;
    EXPECT_EQ(check_sampling(p), "");
    p.confidence = 1;
    EXPECT_TRUE(contains(check_sampling(p), "confidence")) << check_sampling(p);
    p.confidence = 0.9;
    p.variance = 0;
    EXPECT_TRUE(contains(check_sampling(p), "variance")) << check_sampling(p);
}

TEST(Params, CameraRefusesDegenerateCombinations)
{
    CameraParams nothing;
    std::string message = check_camera(nothing);
    EXPECT_TRUE(contains(message, "main_lens") && contains(message, "microlens_array")) << message;

    // Pinhole main lens with a pinhole array.
    CameraParams pp;
    pp.main.given = true;
    pp.main.type = MainLensType::Pinhole;
    pp.main.has_distance = true;
    pp.main.distance_mm = 50;
    test::add_array(&pp, GridType::Hexagonal, 0.5, 0, 2);
    message = check_camera(pp);
    EXPECT_TRUE(contains(message, "pinhole") && contains(message, "no light reaches the sensor")) << message;

    // Pinhole main lens, thin microlenses with 1 + D/d - D/f = 0: the microlenses image the
    // sensor onto the pinhole.
    CameraParams pt = pp;
    pt.array.lens = MicrolensType::ThinLens;
    pt.array.focal_length_count = 1;
    const double D = 50, d = 2;
    pt.array.focal_lengths_mm[0] = 1.0 / (1.0 / D + 1.0 / d);
    message = check_camera(pt);
    EXPECT_TRUE(contains(message, "image the sensor onto the pinhole") && contains(message, "no light")) << message;
    pt.array.focal_lengths_mm[0] = 1.9;
    EXPECT_EQ(check_camera(pt), "");
    // The same for one type of a multi-focus array.
    pt.array.focal_length_count = 3;
    pt.array.focal_lengths_mm[0] = 1.8;
    pt.array.focal_lengths_mm[1] = 1.0 / (1.0 / D + 1.0 / d);
    pt.array.focal_lengths_mm[2] = 2.1;
    message = check_camera(pt);
    EXPECT_TRUE(contains(message, "onto the pinhole")) << message;

    // Valid cameras.
    EXPECT_EQ(check_camera(plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52)), "");
    EXPECT_EQ(check_camera(thin_lens_camera(50, 4, 52)), "");
    CameraParams bare;
    test::add_array(&bare, GridType::Rectangular, 0.5, 0, 2);
    EXPECT_EQ(check_camera(bare), "");

    // An edge-on array, and an array translated out of the camera.
    CameraParams edge = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52);
    test::set_pose(&edge, 90, 0, 0, 0, 0, 0);
    message = check_camera(edge);
    EXPECT_TRUE(contains(message, "rotate") && contains(message, "90")) << message;
    test::set_pose(&edge, 89.99, 0, 0, 0, 0, 0);
    EXPECT_EQ(check_camera(edge), "");
    test::set_pose(&edge, 0, 0, 0, 0, 0, -2);
    message = check_camera(edge);
    EXPECT_TRUE(contains(message, "translate") && contains(message, "sensor")) << message;
    test::set_pose(&edge, 0, 0, 0, 0, 0, 60);
    message = check_camera(edge);
    EXPECT_TRUE(contains(message, "translate") && contains(message, "main lens")) << message;

    // A bad value anywhere is caught by the camera check too.
    CameraParams bad_scale = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52);
    bad_scale.mm_per_unit = kNaN;
    EXPECT_TRUE(contains(check_camera(bad_scale), "mm_per_unit")) << check_camera(bad_scale);
}


// `samples 1, N` never took a second ray (one sample has no variance).
TEST(Params, AdaptiveSamplingNeedsAMinimumOfTwo)
{
    SamplingParams p;
    p.adaptive = true;
    p.samples_min = 1;
    p.samples_max = 64;
    const std::string message = check_sampling(p);
    EXPECT_TRUE(contains(message, "at least 2") && contains(message, "samples N")) << message;
    p.samples_min = 2;
    EXPECT_EQ(check_sampling(p), "");
    EXPECT_NE(check_adaptive_minimum(1), "");
    EXPECT_EQ(check_adaptive_minimum(2), "");
    // The fixed form keeps accepting one sample.
    p = SamplingParams();
    p.samples = 1;
    EXPECT_EQ(check_sampling(p), "");
}

// A degenerate placement wrote metadata the project's own reader refused.
TEST(Params, PlacementMustSpanSpace)
{
    const double x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
    const double long_x[3] = {1.33, 0, 0}, skew[3] = {1, 1, 0.5}, nan[3] = {kNaN, 0, 1};
    const double nearly_x[3] = {1, 1e-12, 0};
    EXPECT_EQ(check_placement(x, y, z), "");
    EXPECT_EQ(check_placement(long_x, y, z), "");      // POV-Ray's right has the aspect ratio's length
    EXPECT_EQ(check_placement(skew, y, z), "");        // not orthogonal, but spans space
    std::string m = check_placement(zero, y, z);
    EXPECT_TRUE(contains(m, "right") && contains(m, "non-zero")) << m;
    m = check_placement(x, zero, z);
    EXPECT_TRUE(contains(m, "up")) << m;
    m = check_placement(x, y, zero);
    EXPECT_TRUE(contains(m, "direction")) << m;
    m = check_placement(x, x, z);
    EXPECT_TRUE(contains(m, "parallel")) << m;
    m = check_placement(x, nearly_x, z);
    EXPECT_TRUE(contains(m, "parallel")) << m;
    const double in_plane[3] = {1, 1, 0};
    m = check_placement(x, y, in_plane);              // direction in the plane of right and up
    EXPECT_TRUE(contains(m, "one plane")) << m;
    EXPECT_NE(check_placement(nan, y, z), "");
}

} // namespace
} // namespace plenoptic
