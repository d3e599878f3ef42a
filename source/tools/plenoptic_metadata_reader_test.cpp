// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the metadata reader: what the writer writes reads back to the same camera; text that
// is not strict JSON in UTF-8 (invalid bytes, lone surrogates, duplicate keys, truncation) is
// refused with one line that says why.

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "plenoptic/truth/metadata.h"
#include "plenoptic_metadata_reader.h"
#include "plenoptic/optics.h"

namespace plenoptic {
namespace {

const CameraFrame kFrame = {{0.1, 0.2, -0.3}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

CameraParams hexagonal_camera()
{
    CameraParams p;
    p.main.given = true;
    p.main.type = MainLensType::ThinLens;
    p.main.has_focal_length = true;
    p.main.focal_length_mm = 16;
    p.main.has_f_number = true;
    p.main.f_number = 4;
    p.main.has_focus_distance = true;
    p.main.focus_distance_units = 2;
    p.array.given = true;
    p.array.grid = GridType::Hexagonal;
    p.array.has_pitch = true;
    p.array.pitch_mm = 0.15;
    p.array.has_lens = true;
    p.array.lens = MicrolensType::ThinLens;
    p.array.focal_length_count = 1;
    p.array.focal_lengths_mm[0] = 0.6;
    p.array.has_distance = true;
    p.array.distance_mm = 0.6;
    p.array.rotate_deg[2] = 0.3;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.01;
    return p;
}

std::string good_text(const std::string& depth_map = "scene.depth.exr")
{
    const CameraParams p = hexagonal_camera();
    return metadata_json(with_film(make_camera(p), 320, 240), p, kFrame, depth_map);
}

// The text with its first `from` replaced by `to`.
std::string edited(const std::string& text, const std::string& from, const std::string& to)
{
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    std::string out = text;
    if (at != std::string::npos)
        out.replace(at, from.size(), to);
    return out;
}

// The refusal message for `text` (a test failure when it is accepted).
std::string refusal(const std::string& text)
{
    const std::string error = parse_metadata(text).error;
    if (error.empty()) {
        ADD_FAILURE() << "accepted:\n" << text;
        return "";
    }
    // One line of printable ASCII, whatever bytes the file held.
    for (unsigned char c : error)
        EXPECT_TRUE(c >= 0x20 && c < 0x7f) << "byte " << int(c) << " in: " << error;
    return error;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(MetadataReader, ReadsWhatTheWriterWrites)
{
    const MetadataReading reading = parse_metadata(good_text());
    ASSERT_TRUE(reading.ok()) << reading.error;
    const RenderMetadata& metadata = reading.metadata;
    const CameraParams p = hexagonal_camera();
    const PlenopticCamera m = make_camera(p);
    EXPECT_EQ(metadata.width, 320);
    EXPECT_EQ(metadata.height, 240);
    EXPECT_EQ(metadata.depth_map, "scene.depth.exr");
    EXPECT_EQ(metadata.frame.location.z, -0.3);
    // Shortest round-trip numbers: every value reads back bit for bit.
    EXPECT_EQ(metadata.model.distance_mm, m.distance_mm);
    EXPECT_EQ(metadata.model.array.pitch_mm, 0.15);
    EXPECT_EQ(metadata.model.array.focal_length_mm(LensIndex{0, 0}), 0.6);
    EXPECT_EQ(metadata.model.sensor.z_mm, m.sensor.z_mm);
    EXPECT_EQ(metadata.params.array.rotate_deg[2], 0.3);
}

// A real lens with a conic and an aspheric surface: the reader gives back the same terms, so
// plenoptic-project traces the lens the render traced.
TEST(MetadataReader, ReadsAConicAndAsphericLensBack)
{
    CameraParams p = hexagonal_camera();
    p.main = MainLensParams();
    p.main.given = true;
    p.main.type = MainLensType::Prescription;
    p.main.has_prescription = true;
    const ParsedPrescription lens = parse_lens_file("0 2 0 10\n60 5 1.5 20 0 -0.5 1e-6 -3e-9\n-60 40 1 20 0 0 -2e-6\n");
    ASSERT_FALSE(lens.error.any()) << lens.error.message;
    p.main.prescription = lens.prescription;
    p.main.has_distance = true;
    p.main.distance_mm = paraxial_image_distance(lens.prescription, INFINITY).mm - 0.6;
    const std::string text = metadata_json(with_film(make_camera(p), 320, 240), p, kFrame, "scene.depth.exr");
    const MetadataReading reading = parse_metadata(text);
    ASSERT_TRUE(reading.ok()) << reading.error;
    const std::vector<LensSurface>& read = reading.metadata.params.main.prescription.surfaces;
    ASSERT_EQ(read.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        const LensSurface& s = lens.prescription.surfaces[i];
        EXPECT_EQ(read[i].conic, s.conic) << i;
        EXPECT_EQ(read[i].aspheric_count, s.aspheric_count) << i;
        for (int j = 0; j < LensSurface::kMaxAspheric; ++j)
            EXPECT_EQ(read[i].aspheric[j], s.aspheric[j]) << i << " " << j;
    }
}

// An array with drawn manufacturing errors, a fill factor and a mask: the reader draws the same
// lenses again, so plenoptic-project projects through the array the render traced.
TEST(MetadataReader, ReadsAnArrayWithErrorsBack)
{
    CameraParams p = hexagonal_camera();
    p.array.has_errors = true;
    p.array.errors.position_sd_mm = 0.003;
    p.array.errors.position_sd_z_mm = 0.001;
    p.array.errors.focal_sd = 0.02;
    p.array.errors.rotation_deg = 2;
    p.array.errors.seed = 17;
    p.array.fill_factor = 0.8;
    p.array.mask = true;
    const PlenopticCamera m = with_film(make_camera(p), 320, 240);
    const MetadataReading reading = parse_metadata(metadata_json(m, p, kFrame, "scene.depth.exr"));
    ASSERT_TRUE(reading.ok()) << reading.error;
    const MicrolensArray& read = reading.metadata.model.array;
    ASSERT_TRUE(read.errors != nullptr);
    EXPECT_EQ(read.fill_factor, 0.8);
    EXPECT_TRUE(read.mask);
    EXPECT_FALSE(read.baffles);
    for (int k = -4; k <= 4; ++k) {
        const LensIndex lens{k, 3 - 2 * k};
        const Vec3 a = m.array.centre_mm(lens), b = read.centre_mm(lens);
        EXPECT_EQ(a.x, b.x);
        EXPECT_EQ(a.z, b.z);
        EXPECT_EQ(m.array.focal_length_mm(lens), read.focal_length_mm(lens));
        EXPECT_EQ(m.array.error_of(lens).tilt_deg, read.error_of(lens).tilt_deg);
        EXPECT_NE(a.x, m.array.to_optics(Vec3{m.array.lattice_centre_local(lens).x, 0, 0}).x);
    }
    // Errors from a lens table need the microimages file beside the metadata file.
    const std::string tabled = edited(metadata_json(m, p, kFrame, "scene.depth.exr"), "\"source\": \"drawn\"",
                                      "\"source\": \"lens_table\"");
    EXPECT_TRUE(contains(refusal(tabled), "microlens_array.errors")) << refusal(tabled);
}

TEST(MetadataReader, AcceptsUtf8AndSurrogatePairs)
{
    // "\u00e9" escaped, U+1F600 as a surrogate pair, and raw UTF-8.
    const std::string text = edited(good_text(), "\"scene.depth.exr\"", "\"sc\\u00e9ne \\ud83d\\ude00 \xc3\xa9.exr\"");
    const MetadataReading reading = parse_metadata(text);
    ASSERT_TRUE(reading.ok()) << reading.error;
    EXPECT_EQ(reading.metadata.depth_map, "sc\xc3\xa9ne \xf0\x9f\x98\x80 \xc3\xa9.exr");
}

TEST(MetadataReader, RefusesLoneSurrogates)
{
    // The old hand-written parser turned these into invalid UTF-8 (CESU bytes) and went on.
    for (const char* bad : {"\"\\ud800.exr\"", "\"\\udc00.exr\"", "\"\\ud83d\\u0041.exr\"", "\"x\\ud83d\""}) {
        const std::string error = refusal(edited(good_text(), "\"scene.depth.exr\"", bad));
        EXPECT_TRUE(contains(error, "not valid JSON (line ")) << bad << ": " << error;
        EXPECT_TRUE(contains(error, "surrogate")) << bad << ": " << error;
    }
}

TEST(MetadataReader, RefusesInvalidUtf8)
{
    // Latin-1, a stray continuation byte, an overlong '/', an encoded surrogate, a cut sequence,
    // a code point above U+10FFFF.
    for (const char* bad : {"caf\xe9.exr", "\x80.exr", "\xc0\xaf.exr", "\xed\xa0\x80.exr", "\xe2\x82", "\xf4\x90\x80\x80"}) {
        const std::string error = refusal(edited(good_text(), "scene.depth.exr", bad));
        EXPECT_TRUE(contains(error, "not valid JSON (line ")) << error;
        EXPECT_TRUE(contains(error, "UTF-8")) << error;
    }
    // Outside a string too.
    EXPECT_TRUE(contains(refusal(edited(good_text(), "\"version\"", "\xef\xbb\xbf\"version\"")), "not valid JSON"));
}

TEST(MetadataReader, RefusesDuplicateKeys)
{
    // The old parser took the first of two, Python's json takes the last: refused instead.
    const std::string text = good_text();
    std::string error = refusal(edited(text, "\"mm_per_unit\": 1000,", "\"mm_per_unit\": 1000,\n  \"mm_per_unit\": 10,"));
    EXPECT_EQ(error, "duplicate key 'mm_per_unit' in the top-level object: a key may appear only once in an object");
    // The same value twice is still a duplicate.
    error = refusal(edited(text, "\"mm_per_unit\": 1000,", "\"mm_per_unit\": 1000,\n  \"mm_per_unit\": 1000,"));
    EXPECT_TRUE(contains(error, "duplicate key 'mm_per_unit'")) << error;
    // Nested, named by its object.
    error = refusal(edited(text, "\"pitch_mm\": 0.15,", "\"pitch_mm\": 0.15,\n    \"pitch_mm\": 0.3,"));
    EXPECT_TRUE(contains(error, "duplicate key 'pitch_mm' in the object 'microlens_array'")) << error;
    error = refusal(edited(text, "\"VMax\":", "\"VMax\": 1, \"VMax\":"));
    EXPECT_TRUE(contains(error, "'lftoolbox_lenslet_grid_model'")) << error;
    // The same key in two different objects is fine (distance_mm is in main_lens and microlens_array).
    EXPECT_EQ(parse_metadata(text).error, "");
}

TEST(MetadataReader, RefusesTruncatedAndMalformedText)
{
    const std::string text = good_text();
    for (size_t cut : {size_t(0), size_t(1), text.size() / 3, text.size() / 2, text.size() - 3}) {
        const std::string error = refusal(text.substr(0, cut));
        EXPECT_TRUE(contains(error, "not valid JSON (line ")) << cut << ": " << error;
    }
    EXPECT_TRUE(contains(refusal(text + "x"), "not valid JSON"));
    EXPECT_TRUE(contains(refusal(edited(text, "\"version\": 1,", "\"version\": 1, // comment\n")), "not valid JSON"));
    EXPECT_TRUE(contains(refusal(edited(text, "\"version\": 1,", "\"version\": 1,,")), "not valid JSON"));
    EXPECT_TRUE(contains(refusal(edited(text, "\"mm_per_unit\": 1000", "\"mm_per_unit\": NaN")), "not valid JSON"));
    EXPECT_TRUE(contains(refusal(edited(text, "\"mm_per_unit\": 1000", "\"mm_per_unit\": 1e400")), "not valid JSON"));
    EXPECT_TRUE(contains(refusal(std::string("{\"a\": \"x\0y\"}", 12)), "not valid JSON"));
    EXPECT_TRUE(contains(refusal(std::string(100000, '[')), "not valid JSON"));
    // A number where a whole number is needed.
    EXPECT_TRUE(contains(refusal(edited(text, "\"width\": 320", "\"width\": 320.0")), "field 'image.width'"));
    // Strings in messages are escaped, one line.
    const std::string error = refusal(edited(text, "\"hexagonal\"", "\"hex\\nagonal\""));
    EXPECT_TRUE(contains(error, "field 'microlens_array.grid' must be \"hexagonal\" or \"rectangular\", found the "
                                "string \"hex\\nagonal\"")) << error;
}

TEST(MetadataReader, ExtremeShiftsKeepALatticeTheReaderTakesBack)
{
    // An array shifted 1e300 mm sideways once passed the checks and its lattice in pixels
    // overflowed (the writer wrote null); shifts are now bounded as lengths are. The largest
    // accepted shift under the smallest pixels still has a finite lattice, written and read back.
    CameraParams p = hexagonal_camera();
    p.array.translate_mm[0] = 1e300;
    EXPECT_TRUE(contains(check_camera(p), "translate")) << check_camera(p);
    p.array.translate_mm[0] = 1e12;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 1e-12;
    ASSERT_EQ(check_camera(p), "");
    const std::string text = metadata_json(with_film(make_camera(p), 320, 240), p, kFrame, "");
    ASSERT_FALSE(contains(text, "\"microimage_lattice\": null")) << text;
    EXPECT_EQ(parse_metadata(text).error, "");
    // A lattice may not be dropped.
    const std::string error = refusal(edited(good_text(), "\"microimage_lattice\": {", "\"microimage_lattice\": null, \"x\": {"));
    EXPECT_TRUE(contains(error, "field 'microimage_lattice' must be an object")) << error;
}

TEST(MetadataReader, FileErrors)
{
    EXPECT_EQ(read_metadata_file("/nonexistent/x.plenoptic.json").error, "cannot open the metadata file");
    char path[] = "/tmp/metadata_reader_testXXXXXX";
    const int fd = mkstemp(path);
    ASSERT_GE(fd, 0);
    close(fd);
    {
        std::ofstream out(path, std::ios::binary);
        out << edited(good_text(), "\"scene.depth.exr\"", "\"\\ud800\"");
    }
    const MetadataReading refused = read_metadata_file(path);
    EXPECT_FALSE(refused.ok());
    EXPECT_TRUE(contains(refused.error, "surrogate")) << refused.error;
    {
        std::ofstream out(path, std::ios::binary);
        out << good_text();
    }
    const MetadataReading read = read_metadata_file(path);
    EXPECT_TRUE(read.ok()) << read.error;
    std::remove(path);
}

} // namespace
} // namespace plenoptic
