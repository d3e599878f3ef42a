// SPDX-License-Identifier: AGPL-3.0-or-later
// Ground truth written beside a plenoptic render: the metadata JSON and, on request, the
// depth map. The renderer registers its camera and fills the depth buffer; the front end
// calls sidecar_write() right after it has written the image, so a render that never
// writes its image leaves no metadata behind.

#ifndef POVRAY_GLUE_PLENOPTIC_SIDECAR_H
#define POVRAY_GLUE_PLENOPTIC_SIDECAR_H

#include <memory>
#include <string>

#include "plenoptic/plenoptic_metadata.h"
#include "povray_glue/plenoptic_setup.h"

namespace plenoptic {

// Names of the files beside an image `dir/name.ext`.
std::string metadata_path_for(const std::string& image_path);  // dir/name.plenoptic.json
std::string depth_path_for(const std::string& image_path);     // dir/name.depth.exr

// What every pixel of the render needs from the registration.
struct RenderState {
    CameraFrame frame;  // the optics frame in the scene, as registered
    bool frame_orthonormal;  // right, up, direction orthonormal: a unit optics direction stays unit
    float* depth;       // W*H floats, row-major, top row first; nullptr when no depth map was asked for
};

// The state registered for this camera and image size, or nullptr: cheap, called for every pixel.
const RenderState* sidecar_current(const CameraSetup* setup, int W, int H);

// Registers the render (first pixel of each thread; later calls for the same camera and size
// return the same state).
const RenderState* sidecar_register(const std::shared_ptr<const CameraSetup>& setup, const CameraFrame& frame, int W, int H);

// The next row of the depth map for the calling thread to fill, or -1 once every row is
// claimed. The whole map is filled at the start of a render (a continued +C render too, which
// re-renders only some pixels), each row by the one thread that claimed it.
int sidecar_claim_depth_row();

// Writes the files for the image just written (if a plenoptic camera rendered it) and forgets
// the registration. Returns false, with a message on stderr, when a file could not be written;
// files are written to a temporary name and renamed, never left half-written.
bool sidecar_write(const std::string& image_path, int W, int H);

} // namespace plenoptic

#endif
