// SPDX-License-Identifier: AGPL-3.0-or-later
// The render's metadata file (docs/metadata.md) as JSON text, from the model alone.

#ifndef PLENOPTIC_METADATA_H
#define PLENOPTIC_METADATA_H

#include <string>

#include "plenoptic_model.h"

namespace plenoptic {

// Where the optics frame sits in the scene (scene units; the three axes unit length).
struct CameraFrame {
    double location[3];   // main-lens centre (array centre when there is no main lens)
    double right[3];      // +x of the optics frame
    double up[3];         // +y
    double direction[3];  // +z, towards the scene
};

// The JSON of docs/metadata.md for a W x H render. `depth_map_file` empty writes null.
// Numbers are written with %.17g; a number that is not finite is written as null.
std::string metadata_json(const Model& model, const CameraParams& params, int W, int H,
                          const CameraFrame& frame, const std::string& depth_map_file);

} // namespace plenoptic

#endif
