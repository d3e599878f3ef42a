// SPDX-License-Identifier: AGPL-3.0-or-later
// The front end's two hooks for a plenoptic render (patch 0005): before it writes the image, the
// stages that change the picture (diffraction); right after, the files beside the image (the
// metadata JSON, the depth map, the microimage centres, the sensor's raw, the white images), so
// a render that never writes its image leaves no metadata behind. Both run the render's list of
// outputs (outputs/output.h) for the render of the view whose image it is.

#ifndef POVRAY_GLUE_PLENOPTIC_SIDECAR_H
#define POVRAY_GLUE_PLENOPTIC_SIDECAR_H

#include <string>

namespace pov_base {
class Image;
class GammaCurve;
}

namespace plenoptic {

// Before the front end writes the image of view `view` (POV-Ray's view id): when a plenoptic
// camera rendered it, the stages that change the picture as a whole, in linear light
// (`working_gamma`: the image's working gamma; nullptr: linear), so the image, its raw and
// everything read from it carry them. Returns false, with a message on stderr, when the image may
// not be written (diffraction cancelled by Ctrl-C, or a continued render (+C), whose earlier part
// was diffracted already): it would not be what the metadata describes.
bool sidecar_prepare_image(int view, pov_base::Image& image, const pov_base::GammaCurve* working_gamma);

// Writes the files for the image of view `view` just written (if a plenoptic camera rendered it:
// the view's render, which this takes). `image`: the picture as rendered, in the working gamma
// `working_gamma` (nullptr: linear), which the sensor's raw reads. Returns false, with a message
// on stderr, when a file could not be written; files are written to a temporary name and renamed,
// never left half-written.
bool sidecar_write(int view, const std::string& image_path, const pov_base::Image& image,
                   const pov_base::GammaCurve* working_gamma);

} // namespace plenoptic

#endif
