// SPDX-License-Identifier: AGPL-3.0-or-later
// What the parser hands the renderer for a `camera { plenoptic ... }`: the checked
// parameters, the model precomputed from them, and the requested ground-truth outputs.

#ifndef POVRAY_GLUE_PLENOPTIC_SETUP_H
#define POVRAY_GLUE_PLENOPTIC_SETUP_H

#include <string>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/sensor/white_image.h"

namespace plenoptic {

struct CameraSetup {
    CameraParams params;
    PlenopticCamera model;
    bool depth_map = false;  // write <output>.depth.exr beside the image
    // <output>.microimages.csv: `microimage_centres` on or off; by default written only where the
    // centres leave the metadata's lattice (a traced prescription, a thin lens with distortion).
    enum MicroimageCentres { kDefault, kWrite, kDoNotWrite };
    MicroimageCentres microimage_centres = kDefault;
    // `microimage_error_anchors N`: refracting microlenses with manufacturing errors, the truth
    // corrected from Jacobian anchors N lenses apart (MicroimageOptions::error_anchor_step); 0, the
    // default, measures every lens.
    int microimage_error_anchors = 0;
    // `white_image [f_numbers <N...>] [noise_free]`: <output>.white.png (one per f-number).
    WhiteImageRequest white_image;

    // Where the camera's last placement keyword (location, look_at, right, up, ...) stands in
    // the scene file: the parser names it when the placement POV-Ray resolves is degenerate.
    struct KeywordSource {
        std::string keyword;
        long line = 0;
        long column = 0;
        long long offset = 0;
    };
    KeywordSource last_placement;
    // Where white_image's f_numbers was written (keyword empty: not written): a value the camera
    // cannot take is refused there.
    KeywordSource white_f_numbers;
};

} // namespace plenoptic

#endif
