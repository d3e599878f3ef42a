// SPDX-License-Identifier: AGPL-3.0-or-later
// Reads a render's metadata file (docs/metadata.md) back into the camera model, so that tools
// can apply the very optics the render used: forward projection from world points to pixels.

#ifndef PLENOPTIC_TOOLS_METADATA_READER_H
#define PLENOPTIC_TOOLS_METADATA_READER_H

#include <string>
#include <vector>

#include "plenoptic/truth/metadata.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/optics.h"
#include "plenoptic/camera/params.h"

namespace plenoptic {

struct RenderMetadata {
    int width = 0;
    int height = 0;
    CameraParams params;  // rebuilt from the resolved values (D as distance_mm)
    PlenopticCamera model;
    CameraFrame frame = CameraFrame();  // world frame of the optics frame, scene units
    std::string depth_map;// file name of the depth EXR, empty when none
};

// What reading a metadata file gives: the camera it describes, or why it was refused.
struct MetadataReading {
    RenderMetadata metadata;  // the file's camera when ok(); default-constructed otherwise
    std::string error;        // "" when the file was read; else one sentence, the cause first
    bool ok() const { return error.empty(); }
};

// Rebuilds the camera from the text of a metadata file. The text must be strict JSON (RFC 8259,
// parsed by nlohmann-json) in UTF-8: invalid UTF-8, an escaped lone surrogate (\ud800) and a key
// that appears twice in one object are refused. A refusal's error is one sentence with the cause
// first: "not valid JSON (line 3, column 7: ...)", "duplicate key 'mm_per_unit' ...", or naming
// the offending field, e.g. "field 'main_lens.focal_length_mm' must be a positive number, found
// null". Also checks that the stored derived values (sensor plane, principal point, lattice
// origin) agree with the parameters, to catch edited files.
// `folder`: where the metadata file is, for the files it names that the camera needs (the
// microimages file of an array whose errors came from a lens table); "" when there is none.
MetadataReading parse_metadata(const std::string& text, const std::string& folder = "");

// Reads the file, then parse_metadata. Errors start with the cause ("cannot open", "not valid
// JSON (...)", "field ..."); the caller names the file.
MetadataReading read_metadata_file(const std::string& path);

// World point (scene units) -> optics frame (mm): solves location + (x right + y up + z direction)
// / mm_per_unit = world. Not valid when the frame is singular or the result is not finite.
struct OpticsPoint {
    Vec3 mm;
    bool valid;
};
OpticsPoint world_to_optics_mm(const RenderMetadata& metadata, Vec3 world);

// Every pixel position (docs/metadata.md's centre convention) where the world point images, one
// per microlens that sees it; lens indices in row form ((0, 0) without an array).
std::vector<PixelHit> project_world_point(const RenderMetadata& metadata, Vec3 world);

} // namespace plenoptic

#endif
