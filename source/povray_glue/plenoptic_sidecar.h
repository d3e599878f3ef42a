// SPDX-License-Identifier: AGPL-3.0-or-later
// Ground truth written beside a plenoptic render: the metadata JSON, the microimage centres
// (with a main lens and an array) and, on request, the depth map and the sensor's raw. The render publishes its state (plenoptic_render.h) and fills the depth map as it
// renders; the front end calls sidecar_write() right after it has written the image, so a
// render that never writes its image leaves no metadata behind.

#ifndef POVRAY_GLUE_PLENOPTIC_SIDECAR_H
#define POVRAY_GLUE_PLENOPTIC_SIDECAR_H

#include <string>

namespace pov_base {
class Image;
class GammaCurve;
}

namespace plenoptic {

// Names of the files beside an image `dir/name.ext`.
std::string metadata_path_for(const std::string& image_path);  // dir/name.plenoptic.json
std::string depth_path_for(const std::string& image_path);     // dir/name.depth.exr
std::string virtual_depth_path_for(const std::string& image_path);  // dir/name.virtual_depth.exr
std::string microimages_path_for(const std::string& image_path);// dir/name.microimages.csv

std::string raw_path_for(const std::string& image_path);        // dir/name.raw.png

// Before the front end writes the image of a plenoptic render: applies what the camera does to
// the picture as a whole, diffraction (sensor/diffraction.h), in linear light (`working_gamma`:
// the image's working gamma; nullptr: linear), so the image, its raw and everything read from it
// carry it. Returns false, with a message on stderr, when it was cancelled (Ctrl-C) or the render
// was continued (+C: the earlier part was diffracted already): then no image may be written,
// since it would not be what the metadata describes.
bool sidecar_prepare_image(pov_base::Image& image, const pov_base::GammaCurve* working_gamma);

// Writes the files for the image just written (if a plenoptic camera rendered it: the published
// render, which this takes). `image`: the picture as rendered, in the working gamma
// `working_gamma` (nullptr: linear), which the sensor's raw reads. Returns false, with a message
// on stderr, when a file could not be written; files are written to a temporary name and renamed,
// never left half-written.
bool sidecar_write(const std::string& image_path, const pov_base::Image& image, const pov_base::GammaCurve* working_gamma);

} // namespace plenoptic

#endif
