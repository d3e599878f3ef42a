// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the metadata JSON: valid JSON (parsed by nlohmann-json), every documented field in the
// documented order, nulls, numbers in their shortest round-trip form, strings escaped and UTF-8.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "plenoptic/truth/metadata.h"
#include "plenoptic/optics.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;
using Json = nlohmann::ordered_json;

const CameraFrame kFrame = {{0, 0.5, -3}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

bool has(const std::string& json, const std::string& part) { return json.find(part) != std::string::npos; }

SidecarFiles with_microimages(const MicroimageSummary* summary)
{
    SidecarFiles files;
    files.microimages = summary;
    return files;
}

SidecarFiles with_raw(const std::string& raw)
{
    SidecarFiles files;
    files.raw = raw;
    return files;
}

// The document, or a test failure when the text is not strict JSON (RFC 8259, valid UTF-8).
Json parsed(const std::string& text)
{
    try {
        return Json::parse(text);
    } catch (const Json::exception& e) {
        ADD_FAILURE() << "not valid JSON: " << e.what() << "\n" << text;
        return Json();
    }
}

// The shortest decimal that reads back to `value`, as %.{precision}g gives it (the reference the
// writer must match digit for digit; whole numbers below 2^53 without a fraction).
std::string shortest(double value)
{
    char buffer[40];
    for (int precision = 1; precision <= 17; ++precision) {
        std::snprintf(buffer, sizeof buffer, "%.*g", precision, value);
        if (std::strtod(buffer, nullptr) == value)
            break;
    }
    return buffer;
}

// Significant digits of a number token: "0.0078125" -> "78125", "1e+300" -> "1", "-52.3" -> "523".
std::string significant_digits(const std::string& token)
{
    std::string digits;
    for (char c : token) {
        if (c == 'e' || c == 'E')
            break;
        if (c >= '0' && c <= '9')
            digits += c;
    }
    const size_t first = digits.find_first_not_of('0');
    if (first == std::string::npos)
        return "0";
    const size_t last = digits.find_last_not_of('0');
    return digits.substr(first, last - first + 1);
}

// Every number token of a JSON text (outside strings).
std::vector<std::string> number_tokens(const std::string& text)
{
    std::vector<std::string> tokens;
    bool in_string = false;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (in_string) {
            if (c == '\\')
                ++i;
            else if (c == '"')
                in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '-' || (c >= '0' && c <= '9')) {
            const size_t end = text.find_first_of(",]} \n", i);
            tokens.push_back(text.substr(i, end - i));
            i = end - 1;
        }
    }
    return tokens;
}

CameraParams documented_camera()
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 0);
    p.main.has_distance = false;
    p.main.has_focus_distance = true;
    p.main.focus_distance_units = 2.5;
    test::set_pose(&p, 0, 0, 0.5, 0.01, 0, 0);
    return p;
}

TEST(Metadata, PlenopticCameraWritesEveryField)
{
    const CameraParams p = documented_camera();
    ASSERT_EQ(check_camera(p), "");
    const PlenopticCamera m = with_film(make_camera(p), 640, 480);
    const std::string json = metadata_json(m, p, kFrame, "scene.depth.exr");
    parsed(json);
    const char* keys[] = {"\"format\": \"povray-plenoptic-metadata\"", "\"version\": 1", "\"image\"", "\"width\": 640",
                          "\"height\": 480", "\"mm_per_unit\": 1000", "\"camera_frame\"", "\"location\": [0, 0.5, -3]",
                          "\"right\"", "\"up\"", "\"direction\"", "\"main_lens\"", "\"type\": \"thin_lens\"",
                          "\"focal_length_mm\": 50", "\"aperture_mm\": 12.5", "\"f_number\": 4", "\"distance_mm\"",
                          "\"focus_distance\": 2.5", "\"microlens_array\"", "\"grid\": \"hexagonal\"",
                          "\"lens\": \"thin_lens\"", "\"pitch_mm\": 0.5", "\"focal_lengths_mm\": [2]",
                          "\"rotate_deg\": [0, 0, 0.5]", "\"translate_mm\"", "\"sensor\"", "\"pixel_size_mm\"",
                          "\"offset_mm\": [0, 0]", "\"plane_z_mm\"", "\"samples\"", "\"adaptive\": false",
                          "\"min\": 1", "\"max\": 1", "\"confidence\"", "\"variance\": 0.0078125",
                          "\"principal_point_px\": [319.5, 239.5]", "\"microimage_lattice\"", "\"origin_px\"",
                          "\"basis_px\"", "\"index_rule\"", "\"exact\": true", "\"lens_types\": 1",
                          "\"lens_type_rule\"", "\"microimage_diameter_px\"", "\"lftoolbox_lenslet_grid_model\"",
                          "\"HSpacing\"", "\"VSpacing\"", "\"HOffset\"", "\"VOffset\"", "\"Rot\"",
                          "\"Orientation\": \"horz\"", "\"FirstPosShiftRow\"", "\"UMax\"", "\"VMax\"",
                          "\"depth_map\": \"scene.depth.exr\""};
    for (const char* key : keys)
        EXPECT_TRUE(has(json, key)) << "missing " << key << " in\n" << json;
    // D is written even though focus_distance gave it, in its shortest round-trip form.
    EXPECT_TRUE(has(json, "\"distance_mm\": " + shortest(m.distance_mm) + ",")) << shortest(m.distance_mm) << "\n"
                                                                                 << json;
    // Microimage diameter: A d / D / pixel size.
    EXPECT_TRUE(has(json, "\"microimage_diameter_px\": " + shortest(12.5 * 2.0 / m.distance_mm / 0.01))) << json;
}

TEST(Metadata, KeysComeInTheDocumentedOrder)
{
    // docs/metadata.md is the contract: these names, in this order, at every level.
    const CameraParams p = documented_camera();
    const Json doc = parsed(metadata_json(with_film(make_camera(p), 640, 480), p, kFrame, "scene.depth.exr"));
    auto keys = [](const Json& object) {
        std::vector<std::string> names;
        for (auto it = object.begin(); it != object.end(); ++it)
            names.push_back(it.key());
        return names;
    };
    typedef std::vector<std::string> Names;
    EXPECT_EQ(keys(doc), (Names{"format", "version", "image", "mm_per_unit", "camera_frame", "main_lens",
                                "microlens_array", "sensor", "samples", "diffraction", "principal_point_px", "microimage_lattice",
                                "lftoolbox_lenslet_grid_model", "depth_map", "virtual_depth_map", "microimages", "white_images"}));
    EXPECT_EQ(keys(doc["image"]), (Names{"width", "height"}));
    EXPECT_EQ(keys(doc["camera_frame"]), (Names{"location", "right", "up", "direction"}));
    EXPECT_EQ(keys(doc["main_lens"]),
              (Names{"type", "focal_length_mm", "aperture_mm", "f_number", "distance_mm", "focus_distance",
                     "distortion_profile"}));
    EXPECT_EQ(keys(doc["microlens_array"]), (Names{"grid", "lens", "pitch_mm", "focal_lengths_mm", "distance_mm",
                                                    "rotate_deg", "translate_mm"}));
    EXPECT_EQ(keys(doc["sensor"]), (Names{"pixel_size_mm", "offset_mm", "plane_z_mm", "radiometry", "read_out"}));
    EXPECT_EQ(keys(doc["sensor"]["radiometry"]), (Names{"model", "projected_solid_angle_sr", "angular_response"}));
    EXPECT_EQ(keys(doc["samples"]), (Names{"adaptive", "min", "max", "confidence", "variance"}));
    EXPECT_EQ(keys(doc["microimage_lattice"]), (Names{"origin_px", "basis_px", "index_rule", "exact", "lens_types",
                                                       "lens_type_rule", "microimage_diameter_px"}));
    EXPECT_EQ(keys(doc["lftoolbox_lenslet_grid_model"]), (Names{"HSpacing", "VSpacing", "HOffset", "VOffset", "Rot",
                                                                 "Orientation", "FirstPosShiftRow", "UMax", "VMax"}));
}

TEST(Metadata, NumbersAreWrittenInTheirShortestRoundTripForm)
{
    // 0.15 and 2.1 are not exact in binary: %.17g wrote 0.14999999999999999 and 2.1000000000000001.
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.15, 0.6, 0.6, 16, 4, 0);
    p.main.has_distance = false;
    p.main.has_focus_distance = true;
    p.main.focus_distance_units = 2;
    p.array.focal_length_count = 3;
    p.array.focal_lengths_mm[1] = 2.1;
    p.array.focal_lengths_mm[2] = 2.2;
    p.array.distance_mm = 0.6;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.01;
    test::set_pose(&p, 0, 0, 0.3, 0.01, 0, 0);
    ASSERT_EQ(check_camera(p), "");
    const PlenopticCamera m = with_film(make_camera(p), 640, 480);
    const std::string json = metadata_json(m, p, kFrame, "");
    parsed(json);
    EXPECT_TRUE(has(json, "\"pitch_mm\": 0.15,")) << json;
    EXPECT_TRUE(has(json, "\"focal_lengths_mm\": [0.6, 2.1, 2.2]")) << json;
    EXPECT_TRUE(has(json, "\"rotate_deg\": [0, 0, 0.3]")) << json;
    EXPECT_TRUE(has(json, "\"translate_mm\": [0.01, 0, 0]")) << json;
    EXPECT_TRUE(has(json, "\"pixel_size_mm\": [0.01, 0.01]")) << json;
    EXPECT_TRUE(has(json, "\"mm_per_unit\": 1000,")) << json;  // a whole number stays one (no "1000.0")
    // Every number: reads back exactly, with no more significant digits than needed.
    const std::vector<std::string> tokens = number_tokens(json);
    EXPECT_GT(tokens.size(), 40u);
    for (const std::string& token : tokens) {
        const double value = std::strtod(token.c_str(), nullptr);
        EXPECT_EQ(significant_digits(token), significant_digits(shortest(value)))
            << token << " is not the shortest form of " << shortest(value);
    }
}

TEST(Metadata, ExtremeNumbersReadBackExactly)
{
    CameraParams p = plenoptic_camera(GridType::Rectangular, 0.1, 2.0, 2.0, 50, 4, 52);
    p.mm_per_unit = 1e-300;
    test::set_pose(&p, 4503599627370495.5, 0, 1e-9, 1.0 / 3, -5e-324, 0);  // below 2^52, not whole
    PlenopticCamera m = make_camera(p);
    m.sensor.offset_mm[0] = 1e300;  // not from checked input; the writer must still be exact
    m.sensor.offset_mm[1] = 9007199254740994.0;  // whole, above 2^53
    const Json doc = parsed(metadata_json(with_film(m, 64, 48), p, kFrame, ""));
    EXPECT_EQ(doc["mm_per_unit"].get<double>(), 1e-300);
    EXPECT_EQ(doc["microlens_array"]["rotate_deg"][2].get<double>(), 1e-9);
    EXPECT_EQ(doc["microlens_array"]["translate_mm"][0].get<double>(), 1.0 / 3);
    EXPECT_EQ(doc["microlens_array"]["translate_mm"][1].get<double>(), -5e-324);
    EXPECT_EQ(doc["sensor"]["offset_mm"][0].get<double>(), 1e300);
    EXPECT_EQ(doc["sensor"]["offset_mm"][1].get<double>(), 9007199254740994.0);
    EXPECT_EQ(doc["microlens_array"]["rotate_deg"][0].get<double>(), 4503599627370495.5);
}

TEST(Metadata, SensorReadOut)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.1, 0.4, 0.4, 50, 4, 52);
    const PlenopticCamera m = with_film(make_camera(p), 64, 48);
    EXPECT_TRUE(parsed(metadata_json(m, p, kFrame, ""))["sensor"]["read_out"].is_null());
    SensorChainParams& c = p.sensor.chain;
    c.given = true;
    c.bayer = BayerPattern::GRBG;
    c.bit_depth = 10;
    c.full_well_e = 4500;
    c.read_noise_e = 3;
    c.black_level_dn = 64;
    c.seed = 7;
    Json out = parsed(metadata_json(m, p, kFrame, with_raw("scene.raw.png")))["sensor"]["read_out"];
    EXPECT_EQ(out["raw_file"], "scene.raw.png");
    EXPECT_EQ(out["bayer"], "grbg");
    EXPECT_EQ(out["bit_depth"], 10);
    EXPECT_EQ(out["exposure_e"].get<double>(), 4500);  // without `exposure`: the full well
    EXPECT_EQ(out["read_noise_e"].get<double>(), 3);
    EXPECT_EQ(out["black_level_dn"], 64);
    EXPECT_EQ(out["seed"], 7);
    EXPECT_EQ(out["gain_dn_per_e"].get<double>(), (1023.0 - 64) / 4500);
    // Asked for but not written (the file could not be written): the parameters, and no file.
    c.bayer = BayerPattern::None;
    out = parsed(metadata_json(m, p, kFrame, ""))["sensor"]["read_out"];
    EXPECT_TRUE(out["raw_file"].is_null());
    EXPECT_TRUE(out["bayer"].is_null());
}

TEST(Metadata, StringsAreEscapedAndValidUtf8)
{
    CameraParams p = plenoptic_camera(GridType::Rectangular, 0.1, 2.0, 2.0, 50, 4, 52);
    const PlenopticCamera m = with_film(make_camera(p), 64, 48);
    std::string json = metadata_json(m, p, kFrame, "dir\\name \"quoted\"\t\xc3\xa9.exr");
    EXPECT_EQ(parsed(json)["depth_map"].get<std::string>(), "dir\\name \"quoted\"\t\xc3\xa9.exr");
    EXPECT_TRUE(has(json, "\"depth_map\": \"dir\\\\name \\\"quoted\\\"\\t\xc3\xa9.exr\"")) << json;
    // A file name that is not UTF-8 (Latin-1 bytes) cannot be JSON text: each bad byte is written
    // as U+FFFD and the file stays valid.
    json = metadata_json(m, p, kFrame, "caf\xe9\xff.exr");
    EXPECT_EQ(parsed(json)["depth_map"].get<std::string>(), "caf\xef\xbf\xbd\xef\xbf\xbd.exr") << json;
    // A rectangular grid has no LFToolbox row shift.
    EXPECT_TRUE(has(json, "\"FirstPosShiftRow\": null")) << json;
    EXPECT_TRUE(has(json, "\"index_rule\": \"skew indices (k, l): rectangular")) << json;
}

TEST(Metadata, AbsentPartsAreNull)
{
    const CameraParams lens_only = test::thin_lens_camera(50, 4, 52);
    std::string json = metadata_json(with_film(make_camera(lens_only), 64, 48), lens_only, kFrame, "");
    parsed(json);
    EXPECT_TRUE(has(json, "\"microlens_array\": null")) << json;
    EXPECT_TRUE(has(json, "\"microimage_lattice\": null")) << json;
    EXPECT_TRUE(has(json, "\"lftoolbox_lenslet_grid_model\": null")) << json;
    EXPECT_TRUE(has(json, "\"focus_distance\": null")) << json;
    EXPECT_TRUE(has(json, "\"depth_map\": null")) << json;

    CameraParams bare;
    test::add_array(&bare, GridType::Hexagonal, 0.5, 0, 2);
    json = metadata_json(with_film(make_camera(bare), 64, 48), bare, kFrame, "");
    parsed(json);
    EXPECT_TRUE(has(json, "\"type\": \"none\"")) << json;
    EXPECT_TRUE(has(json, "\"focal_length_mm\": null")) << json;
    EXPECT_TRUE(has(json, "\"distance_mm\": null")) << json;
    EXPECT_TRUE(has(json, "\"focal_lengths_mm\": []")) << json;
    EXPECT_TRUE(has(json, "\"lens\": \"pinhole\"")) << json;
    EXPECT_TRUE(has(json, "\"microimage_diameter_px\": null")) << json;

    // Multi-focus arrays state the type rule.
    CameraParams multi = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 52);
    multi.array.focal_length_count = 3;
    multi.array.focal_lengths_mm[1] = 2.1;
    multi.array.focal_lengths_mm[2] = 2.2;
    json = metadata_json(with_film(make_camera(multi), 64, 48), multi, kFrame, "");
    EXPECT_TRUE(has(json, "\"lens_types\": 3")) << json;
    EXPECT_TRUE(has(json, "\"lens_type_rule\": \"type(k, l) = (k - l) mod 3, focal_lengths_mm[type]\"")) << json;
    EXPECT_TRUE(has(json, "\"focal_lengths_mm\": [2, 2.1, 2.2]")) << json;
}

TEST(Metadata, NonFiniteNumbersAreWrittenAsNull)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 52);
    PlenopticCamera m = make_camera(p);
    m.sensor.offset_mm[0] = NAN;  // cannot come from checked input; the writer must still cope
    m.sensor.offset_mm[1] = -INFINITY;
    const std::string json = metadata_json(with_film(m, 64, 48), p, kFrame, "");
    parsed(json);
    EXPECT_TRUE(has(json, "\"offset_mm\": [null, null]")) << json;
    EXPECT_FALSE(has(json, "nan")) << json;
    EXPECT_FALSE(has(json, "inf")) << json;
}

TEST(Metadata, LayoutIsOneMemberPerLineWithArraysOnOneLine)
{
    const CameraParams p = documented_camera();
    const std::string json = metadata_json(with_film(make_camera(p), 640, 480), p, kFrame, "");
    EXPECT_EQ(json.rfind("{\n  \"format\": \"povray-plenoptic-metadata\",\n  \"version\": 1,\n", 0), 0u) << json;
    EXPECT_TRUE(has(json, "\n  \"image\": {\n    \"width\": 640,\n    \"height\": 480\n  },\n")) << json;
    EXPECT_TRUE(has(json, "\n  \"samples\": {\"adaptive\": false, \"min\": ")) << json;
    EXPECT_TRUE(has(json, "\n    \"basis_px\": [[")) << json;
    EXPECT_TRUE(has(json, "\n  \"depth_map\": null,\n")) << json;
    EXPECT_TRUE(has(json, "\n  \"microimages\": null,\n")) << json;
    EXPECT_EQ(json.substr(json.size() - 25), "  \"white_images\": null\n}\n") << json;
}

TEST(Metadata, LatticeFieldsMatchTheMicroimageLattice)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 52);
    test::set_pose(&p, 0, 0, 2, 0, 0, 0);
    const PlenopticCamera m = with_film(make_camera(p), 640, 480);
    const MicroimageLattice lattice = microimage_lattice(m);
    const Json doc = parsed(metadata_json(m, p, kFrame, ""));
    const Json& grid = doc["lftoolbox_lenslet_grid_model"];
    EXPECT_EQ(grid["HSpacing"].get<double>(), lattice.h_spacing);
    EXPECT_EQ(grid["Rot"].get<double>(), lattice.rot);
    EXPECT_EQ(grid["UMax"].get<long long>(), lattice.u_max);
    EXPECT_TRUE(grid["UMax"].is_number_integer());
    const Json& origin = doc["microimage_lattice"]["origin_px"];
    EXPECT_EQ(origin[0].get<double>(), lattice.origin_px[0]);
    EXPECT_EQ(origin[1].get<double>(), lattice.origin_px[1]);
    EXPECT_NEAR(lattice.h_spacing, 0.5 * (1 + 2.0 / 52) / 0.01, 1e-9);
}

TEST(Metadata, MicroimagesSummaryIsWrittenAsGiven)
{
    const CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 52);
    const PlenopticCamera m = with_film(make_camera(p), 640, 480);
    MicroimageSummary summary = MicroimageSummary();
    summary.file = "scene.microimages.csv";
    summary.lenses = 12;
    summary.lit_lenses = 11;
    summary.options = default_microimage_options();
    summary.fit.valid = true;
    summary.fit.origin_px[0] = 319.5;
    summary.fit.origin_px[1] = 239.25;
    summary.fit.basis_a_px[0] = 52;
    summary.fit.basis_b_px[1] = 45.5;
    summary.fit.lenses = 11;
    summary.fit.rms_residual_px = 0.125;
    summary.fit.max_residual_px = 0.5;
    summary.fit.worst = LensIndex{-3, 2};
    summary.from_lattice_rms_px = 0.25;
    summary.from_lattice_max_px = 1.5;
    const Json doc = parsed(metadata_json(m, p, kFrame, with_microimages(&summary)));
    const Json& mi = doc["microimages"];
    std::vector<std::string> names;
    for (auto it = mi.begin(); it != mi.end(); ++it)
        names.push_back(it.key());
    EXPECT_EQ(names, (std::vector<std::string>{"file", "columns", "lenses", "lit_lenses", "integration", "lattice_fit",
                                               "from_microimage_lattice"}));
    EXPECT_EQ(mi["file"], "scene.microimages.csv");
    EXPECT_EQ(mi["lenses"], 12);
    EXPECT_EQ(mi["lit_lenses"], 11);
    EXPECT_EQ(mi["integration"]["aperture_points"], summary.options.aperture_points);
    EXPECT_EQ(mi["lattice_fit"]["origin_px"][1].get<double>(), 239.25);
    EXPECT_EQ(mi["lattice_fit"]["basis_px"][1][1].get<double>(), 45.5);
    EXPECT_EQ(mi["lattice_fit"]["max_residual_lens"], Json::parse("[-3, 2]"));
    EXPECT_EQ(mi["from_microimage_lattice"]["max_px"].get<double>(), 1.5);
    summary.fit.valid = false;
    EXPECT_TRUE(parsed(metadata_json(m, p, kFrame, with_microimages(&summary)))["microimages"]["lattice_fit"].is_null());
}

TEST(Metadata, DistortionProfileOfAThinLensWithDistortion)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 60);
    p.main.has_distortion = true;
    p.main.distortion = DistortionParams{{-0.1, 0, 0}, {0, 0}};
    const Json doc = parsed(metadata_json(with_film(make_camera(p), 640, 480), p, kFrame, ""));
    const Json& profile = doc["main_lens"]["distortion_profile"];
    ASSERT_TRUE(profile.is_object());
    EXPECT_EQ(profile["samples"].size(), 17u);
    EXPECT_EQ(profile["image_plane_z_mm"].get<double>(), -60);
    EXPECT_NEAR(profile["object_plane_z_mm"].get<double>(), 300, 1e-9);
    EXPECT_TRUE(profile["samples"][0][4].is_null());  // no percentage on the axis
    const Json& last = profile["samples"][16];
    const double h = last[2].get<double>(), r = h / 60;
    EXPECT_NEAR(last[4].get<double>(), -10 * r * r, 1e-9);  // 100 * k1 r^2
    // A pinhole main lens has no profile.
    CameraParams pinhole = p;
    pinhole.main.type = MainLensType::Pinhole;
    pinhole.main.has_distortion = false;
    pinhole.array.lens = MicrolensType::ThinLens;
    EXPECT_TRUE(parsed(metadata_json(with_film(make_camera(pinhole), 640, 480), pinhole, kFrame, ""))["main_lens"]["distortion_profile"].is_null());
}

} // namespace
} // namespace plenoptic
