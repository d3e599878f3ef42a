// SPDX-License-Identifier: AGPL-3.0-or-later
// libFuzzer target over the metadata reader (source/tools/plenoptic_metadata_reader.cpp): the
// input bytes are a whole <image>.plenoptic.json. Invariants (else abort()):
//   - a refused file gives a non-empty message of one line of printable ASCII, whatever the bytes;
//   - an accepted file describes a camera check_camera accepts, with a positive image size;
//   - writing the camera read back (metadata_json) gives a file the reader accepts again, with
//     the same camera bit for bit, and writing that one gives the very same text (the writer's
//     numbers read back exactly);
//   - forward projection of a few points gives finite pixel positions inside the image.
//
// Built with clang -fsanitize=fuzzer,address,undefined by fuzz/CMakeLists.txt and run by
// fuzz/run-ci from the seeds in fuzz/corpus-metadata/ (real files, and broken ones: duplicate
// keys, a lone surrogate, invalid UTF-8, truncations); replayed over those seeds with the ordinary
// compiler by tests/robustness (fuzz/replay_main.cpp).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "plenoptic/truth/metadata.h"
#include "plenoptic_metadata_reader.h"
#include "plenoptic/optics.h"
#include "plenoptic/camera/params.h"

namespace {

using namespace plenoptic;

// The kind of a model's main lens and of its microlenses, as the metadata names them ("none"
// without one).
inline std::string lens_kind(const PlenopticCamera& m) { return m.lens ? m.lens->kind_name() : "none"; }
inline std::string microlens_kind(const PlenopticCamera& m)
{
    return m.array.microlens ? m.array.microlens->kind_name() : "none";
}

const std::string* g_text = nullptr;

#define FUZZ_ASSERT(cond, ...)                                                             \
    do {                                                                                   \
        if (!(cond)) {                                                                     \
            std::fprintf(stderr, "plenoptic_metadata_fuzz: invariant failed: %s\n  ", #cond); \
            std::fprintf(stderr, __VA_ARGS__);                                             \
            std::fprintf(stderr, "\n");                                                    \
            if (g_text)                                                                    \
                std::fprintf(stderr, "input (%zu bytes):\n%.4000s\n", g_text->size(),      \
                             g_text->c_str());                                             \
            std::abort();                                                                  \
        }                                                                                  \
    } while (0)

bool one_printable_line(const std::string& message)
{
    if (message.empty())
        return false;
    for (unsigned char c : message)
        if (c < 0x20 || c >= 0x7f)
            return false;
    return true;
}

// Values the reader accepted are finite: equal, 0 and -0 alike.
bool same_double(double a, double b) { return a == b; }

// The camera values the reader fills, compared exactly (0 and -0 alike).
void expect_same_camera(const RenderMetadata& a, const RenderMetadata& b)
{
    FUZZ_ASSERT(a.width == b.width && a.height == b.height, "image %dx%d read back as %dx%d", a.width, a.height,
                b.width, b.height);
    const PlenopticCamera& m = a.model;
    const PlenopticCamera& n = b.model;
    FUZZ_ASSERT(lens_kind(m) == lens_kind(n) && m.array.grid == n.array.grid && microlens_kind(m) == microlens_kind(n) &&
                    m.array.lens_type_count == n.array.lens_type_count,
                "kinds differ after a round trip");
    FUZZ_ASSERT(same_double(m.mm_per_unit, n.mm_per_unit), "mm_per_unit %.17g -> %.17g", m.mm_per_unit, n.mm_per_unit);
    FUZZ_ASSERT(same_double(m.distance_mm, n.distance_mm), "D %.17g -> %.17g", m.distance_mm, n.distance_mm);
    FUZZ_ASSERT(same_double(m.sensor.z_mm, n.sensor.z_mm), "sensor z %.17g -> %.17g", m.sensor.z_mm, n.sensor.z_mm);
    if (lens_kind(m) == "thin_lens") {
        FUZZ_ASSERT(same_double(m.focal_length_mm(), n.focal_length_mm()) && same_double(m.aperture_mm(), n.aperture_mm()),
                    "main lens F %.17g A %.17g -> F %.17g A %.17g", m.focal_length_mm(), m.aperture_mm(),
                    n.focal_length_mm(), n.aperture_mm());
    }
    if (m.array.grid != GridType::None) {
        FUZZ_ASSERT(same_double(m.array.pitch_mm, n.array.pitch_mm) && same_double(m.array.distance_mm, n.array.distance_mm),
                    "pitch %.17g d %.17g -> pitch %.17g d %.17g", m.array.pitch_mm, m.array.distance_mm, n.array.pitch_mm,
                    n.array.distance_mm);
        for (int i = 0; i < 3; ++i)
            FUZZ_ASSERT(same_double(a.params.array.rotate_deg[i], b.params.array.rotate_deg[i]) &&
                            same_double(a.params.array.translate_mm[i], b.params.array.translate_mm[i]),
                        "array pose [%d] differs after a round trip", i);
    }
    for (int i = 0; i < 2; ++i)
        FUZZ_ASSERT(same_double(m.sensor.pixel_size_mm[i], n.sensor.pixel_size_mm[i]) &&
                        same_double(m.sensor.offset_mm[i], n.sensor.offset_mm[i]),
                    "sensor [%d] differs after a round trip", i);
    const auto same_vector = [](Vec3 p, Vec3 q) {
        return same_double(p.x, q.x) && same_double(p.y, q.y) && same_double(p.z, q.z);
    };
    FUZZ_ASSERT(same_vector(a.frame.location, b.frame.location) && same_vector(a.frame.right, b.frame.right) &&
                    same_vector(a.frame.up, b.frame.up) && same_vector(a.frame.direction, b.frame.direction),
                "camera frame differs after a round trip");
    FUZZ_ASSERT(a.depth_map == b.depth_map, "depth_map '%s' -> '%s'", a.depth_map.c_str(), b.depth_map.c_str());
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    g_text = &text;
    const MetadataReading reading = parse_metadata(text);
    if (!reading.ok()) {
        FUZZ_ASSERT(one_printable_line(reading.error), "refusal message not one printable line: '%s'",
                    reading.error.c_str());
        g_text = nullptr;
        return 0;
    }
    const RenderMetadata& metadata = reading.metadata;
    FUZZ_ASSERT(metadata.width >= 1 && metadata.height >= 1, "image %dx%d accepted", metadata.width, metadata.height);
    const std::string problem = check_camera(metadata.params);
    FUZZ_ASSERT(problem.empty(), "accepted a camera check_camera refuses: %s", problem.c_str());
    const PlenopticCamera& m = metadata.model;
    FUZZ_ASSERT(std::isfinite(m.sensor.z_mm) && m.sensor.z_mm < 0, "sensor plane z = %.17g", m.sensor.z_mm);

    // Write what was read, read it again: the same camera, and the same text when written again.
    const std::string written =
        metadata_json(with_film(m, metadata.width, metadata.height), metadata.params, metadata.frame, metadata.depth_map);
    const MetadataReading reread = parse_metadata(written);
    FUZZ_ASSERT(reread.ok(), "the writer's own file is refused: %s\n%s", reread.error.c_str(), written.c_str());
    const RenderMetadata& again = reread.metadata;
    expect_same_camera(metadata, again);
    const std::string rewritten =
        metadata_json(with_film(again.model, again.width, again.height), again.params, again.frame, again.depth_map);
    FUZZ_ASSERT(rewritten == written, "writing the re-read camera changed the text:\n%s\n---\n%s", written.c_str(),
                rewritten.c_str());

    // Forward projection visits every lens that can image into the picture: only where that is a
    // few thousand lenses, to keep the fuzzer fast.
    const double span_mm = std::max(metadata.width * m.sensor.pixel_size_mm[0], metadata.height * m.sensor.pixel_size_mm[1]);
    if (m.array.grid == GridType::None || span_mm <= 64 * m.array.pitch_mm) {
        const double points[3][3] = {{0, 0, 1}, {0.1, -0.05, 2}, {-3, 2, 50}};
        for (const auto& point : points) {
            for (const PixelHit& hit : project_world_point(metadata, Vec3{point[0], point[1], point[2]})) {
                FUZZ_ASSERT(std::isfinite(hit.u) && std::isfinite(hit.v), "projection hit (%g, %g)", hit.u, hit.v);
                FUZZ_ASSERT(hit.u >= -0.5 && hit.u < metadata.width - 0.5 && hit.v >= -0.5 &&
                                hit.v < metadata.height - 0.5,
                            "projection hit (%.17g, %.17g) outside the %dx%d image", hit.u, hit.v, metadata.width,
                            metadata.height);
            }
        }
    }
    g_text = nullptr;
    return 0;
}
