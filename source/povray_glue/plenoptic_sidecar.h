// SPDX-License-Identifier: AGPL-3.0-or-later
// Ground truth written beside a plenoptic render: the metadata JSON, the microimage centres
// (with a main lens and an array) and, on request, the depth map. The render publishes its state (plenoptic_render.h) and fills the depth map as it
// renders; the front end calls sidecar_write() right after it has written the image, so a
// render that never writes its image leaves no metadata behind.

#ifndef POVRAY_GLUE_PLENOPTIC_SIDECAR_H
#define POVRAY_GLUE_PLENOPTIC_SIDECAR_H

#include <string>

namespace plenoptic {

// Names of the files beside an image `dir/name.ext`.
std::string metadata_path_for(const std::string& image_path);  // dir/name.plenoptic.json
std::string depth_path_for(const std::string& image_path);     // dir/name.depth.exr
std::string microimages_path_for(const std::string& image_path);// dir/name.microimages.csv

// Writes the files for the image just written (if a plenoptic camera rendered it: the published
// render, which this takes). Returns false, with a message on stderr, when a file could not be written;
// files are written to a temporary name and renamed, never left half-written.
bool sidecar_write(const std::string& image_path, int W, int H);

} // namespace plenoptic

#endif
