// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the metadata JSON: valid syntax, every documented field, nulls, number format.

#include <cctype>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "plenoptic_metadata.h"
#include "plenoptic_optics.h"
#include "plenoptic_test_util.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;

// A strict little JSON syntax checker (RFC 8259 grammar, no extensions).
class JsonChecker {
public:
    explicit JsonChecker(const std::string& text) : s_(text) {}
    bool valid()
    {
        skip();
        if (!value())
            return false;
        skip();
        return i_ == s_.size();
    }

private:
    void skip()
    {
        while (i_ < s_.size() && std::isspace((unsigned char)s_[i_]))
            ++i_;
    }
    bool literal(const char* word)
    {
        const std::string w(word);
        if (s_.compare(i_, w.size(), w) != 0)
            return false;
        i_ += w.size();
        return true;
    }
    bool string()
    {
        if (s_[i_] != '"')
            return false;
        for (++i_; i_ < s_.size(); ++i_) {
            const unsigned char c = s_[i_];
            if (c == '"') {
                ++i_;
                return true;
            }
            if (c < 0x20)
                return false;
            if (c == '\\')
                ++i_;
        }
        return false;
    }
    bool number()
    {
        const size_t start = i_;
        if (s_[i_] == '-')
            ++i_;
        if (i_ >= s_.size() || !std::isdigit((unsigned char)s_[i_]))
            return false;
        if (s_[i_] == '0')
            ++i_;
        else
            while (i_ < s_.size() && std::isdigit((unsigned char)s_[i_]))
                ++i_;
        if (i_ < s_.size() && s_[i_] == '.') {
            ++i_;
            if (!std::isdigit((unsigned char)s_[i_]))
                return false;
            while (std::isdigit((unsigned char)s_[i_]))
                ++i_;
        }
        if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
            ++i_;
            if (s_[i_] == '+' || s_[i_] == '-')
                ++i_;
            if (!std::isdigit((unsigned char)s_[i_]))
                return false;
            while (std::isdigit((unsigned char)s_[i_]))
                ++i_;
        }
        return i_ > start;
    }
    bool value()
    {
        skip();
        if (i_ >= s_.size())
            return false;
        const char c = s_[i_];
        if (c == '{' || c == '[') {
            const char close = c == '{' ? '}' : ']';
            ++i_;
            skip();
            if (s_[i_] == close) {
                ++i_;
                return true;
            }
            for (;;) {
                skip();
                if (c == '{') {
                    if (!string())
                        return false;
                    skip();
                    if (s_[i_++] != ':')
                        return false;
                }
                if (!value())
                    return false;
                skip();
                if (s_[i_] == ',') {
                    ++i_;
                    continue;
                }
                if (s_[i_] == close) {
                    ++i_;
                    return true;
                }
                return false;
            }
        }
        if (c == '"')
            return string();
        if (c == 't')
            return literal("true");
        if (c == 'f')
            return literal("false");
        if (c == 'n')
            return literal("null");
        return number();
    }

    const std::string& s_;
    size_t i_ = 0;
};

const CameraFrame kFrame = {{0, 0.5, -3}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

bool has(const std::string& json, const std::string& part) { return json.find(part) != std::string::npos; }

TEST(Metadata, PlenopticCameraWritesEveryField)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 0);
    p.main.has_distance = false;
    p.main.has_focus_distance = true;
    p.main.focus_distance_units = 2.5;
    test::set_pose(&p, 0, 0, 0.5, 0.01, 0, 0);
    ASSERT_EQ(check_camera(p), "");
    const Model m = make_model(p);
    const std::string json = metadata_json(m, p, 640, 480, kFrame, "scene.depth.exr");
    EXPECT_TRUE(JsonChecker(json).valid()) << json;
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
    // D is written even though focus_distance gave it; %.17g throughout.
    char expected_d[64];
    std::snprintf(expected_d, sizeof expected_d, "\"distance_mm\": %.17g", m.distance_mm);
    EXPECT_TRUE(has(json, expected_d)) << expected_d << "\n" << json;
    // Microimage diameter: A d / D / pixel size.
    char expected_diameter[80];
    std::snprintf(expected_diameter, sizeof expected_diameter, "\"microimage_diameter_px\": %.17g",
                  12.5 * 2.0 / m.distance_mm / 0.01);
    EXPECT_TRUE(has(json, expected_diameter)) << expected_diameter << "\n" << json;
}

TEST(Metadata, NumbersUseSeventeenDigitsAndStringsAreEscaped)
{
    CameraParams p = plenoptic_camera(GridType::Rectangular, 0.1, 2.0, 2.0, 50, 4, 52);
    const Model m = make_model(p);
    const std::string json = metadata_json(m, p, 64, 48, kFrame, "dir\\name \"quoted\".exr");
    EXPECT_TRUE(JsonChecker(json).valid()) << json;
    EXPECT_TRUE(has(json, "\"pitch_mm\": 0.10000000000000001")) << json;
    EXPECT_TRUE(has(json, "\"depth_map\": \"dir\\\\name \\\"quoted\\\".exr\"")) << json;
    // A rectangular grid has no LFToolbox row shift.
    EXPECT_TRUE(has(json, "\"FirstPosShiftRow\": null")) << json;
    EXPECT_TRUE(has(json, "\"index_rule\": \"skew indices (k, l): rectangular")) << json;
}

TEST(Metadata, AbsentPartsAreNull)
{
    const CameraParams lens_only = test::thin_lens_camera(50, 4, 52);
    std::string json = metadata_json(make_model(lens_only), lens_only, 64, 48, kFrame, "");
    EXPECT_TRUE(JsonChecker(json).valid()) << json;
    EXPECT_TRUE(has(json, "\"microlens_array\": null")) << json;
    EXPECT_TRUE(has(json, "\"microimage_lattice\": null")) << json;
    EXPECT_TRUE(has(json, "\"lftoolbox_lenslet_grid_model\": null")) << json;
    EXPECT_TRUE(has(json, "\"focus_distance\": null")) << json;
    EXPECT_TRUE(has(json, "\"depth_map\": null")) << json;

    CameraParams bare;
    test::add_array(&bare, GridType::Hexagonal, 0.5, 0, 2);
    json = metadata_json(make_model(bare), bare, 64, 48, kFrame, "");
    EXPECT_TRUE(JsonChecker(json).valid()) << json;
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
    json = metadata_json(make_model(multi), multi, 64, 48, kFrame, "");
    EXPECT_TRUE(has(json, "\"lens_types\": 3")) << json;
    EXPECT_TRUE(has(json, "\"lens_type_rule\": \"type(k, l) = (k - l) mod 3, focal_lengths_mm[type]\"")) << json;
    EXPECT_TRUE(has(json, "\"focal_lengths_mm\": [2, 2.1000000000000001, 2.2000000000000002]")) << json;
}

TEST(Metadata, NonFiniteNumbersAreWrittenAsNull)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 52);
    Model m = make_model(p);
    m.sensor_offset_mm[0] = NAN;  // cannot come from checked input; the writer must still cope
    const std::string json = metadata_json(m, p, 64, 48, kFrame, "");
    EXPECT_TRUE(JsonChecker(json).valid()) << json;
    EXPECT_TRUE(has(json, "\"offset_mm\": [null, 0]")) << json;
    EXPECT_FALSE(has(json, "nan")) << json;
}

TEST(Metadata, LatticeFieldsMatchTheMicroimageLattice)
{
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2.0, 2.0, 50, 4, 52);
    test::set_pose(&p, 0, 0, 2, 0, 0, 0);
    const Model m = make_model(p);
    const MicroimageLattice lattice = microimage_lattice(m, 640, 480);
    const std::string json = metadata_json(m, p, 640, 480, kFrame, "");
    char field[80];
    std::snprintf(field, sizeof field, "\"HSpacing\": %.17g", lattice.h_spacing);
    EXPECT_TRUE(has(json, field)) << field;
    std::snprintf(field, sizeof field, "\"Rot\": %.17g", lattice.rot);
    EXPECT_TRUE(has(json, field)) << field;
    std::snprintf(field, sizeof field, "\"origin_px\": [%.17g, %.17g]", lattice.origin_px[0], lattice.origin_px[1]);
    EXPECT_TRUE(has(json, field)) << field;
    EXPECT_NEAR(lattice.h_spacing, 0.5 * (1 + 2.0 / 52) / 0.01, 1e-9);
}

} // namespace
} // namespace plenoptic
