// SPDX-License-Identifier: AGPL-3.0-or-later
// The render's metadata file (docs/metadata.md) as JSON text, from the model alone.

#ifndef PLENOPTIC_METADATA_H
#define PLENOPTIC_METADATA_H

#include <string>
#include <vector>

#include "plenoptic/truth/microimages.h"
#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// Where the optics frame sits in the scene (scene units; the three axes unit length).
struct CameraFrame {
    Vec3 location;   // main-lens centre (array centre when there is no main lens)
    Vec3 right;      // +x of the optics frame
    Vec3 up;         // +y
    Vec3 direction;  // +z, towards the scene
};

// The JSON of docs/metadata.md for a W x H render (written with nlohmann-json, members in the
// documented order). A file name that is not UTF-8 has each invalid byte replaced by U+FFFD. Numbers are written in the shortest form that reads back to
// the same double (0.15), whole numbers below 2^53 without a fraction (1000); a number that is
// not finite is written as null.
// A white image written beside the image (sensor/white_image.h).
struct WhiteImageFile {
    std::string file;
    double f_number;   // the main lens's f-number it was computed at (0: no main lens aperture)
    bool raw;          // true: DN through the sensor's read-out; false: the linear value x 65535 / scale
    double scale = 1;  // linear: a power of two >= the largest value, so that none clips (1: none above 1)
};

// The files written beside the image, as the metadata names them (empty or nullptr: null).
// `depth_map`: the depth EXR; `virtual_depth_map`: the virtual-depth EXR of a focused camera;
// `microimages`: the summary of the microimages file; `raw`: the sensor's raw
// (sensor.read_out.raw_file; "" gives null there: asked for but not written); `white_images`:
// the white images written (null in the JSON when none was asked for). Built from a depth map's
// name alone for the common case.
struct SidecarFiles {
    std::string depth_map;
    std::string virtual_depth_map;
    const MicroimageSummary* microimages = nullptr;
    std::string raw;
    const std::vector<WhiteImageFile>* white_images = nullptr;

    SidecarFiles() {}
    SidecarFiles(const std::string& depth_map_file) : depth_map(depth_map_file) {}
    SidecarFiles(const char* depth_map_file) : depth_map(depth_map_file) {}
};

std::string metadata_json(const PlenopticCamera& model, const CameraParams& params,
                          const CameraFrame& frame, const SidecarFiles& files = SidecarFiles());

} // namespace plenoptic

#endif
