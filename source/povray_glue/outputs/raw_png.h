// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor's raw as a 16-bit PNG: grey for a Bayer mosaic, RGB otherwise, the values
// the DN themselves (no scaling), with an sBIT chunk giving the sensor's bit depth.

#ifndef POVRAY_GLUE_OUTPUTS_RAW_PNG_H
#define POVRAY_GLUE_OUTPUTS_RAW_PNG_H

#include <cstdint>
#include <string>
#include <vector>

namespace plenoptic {

// The PNG file's bytes for W x H pixels of `channels` (1 or 3) values each, rows from the top;
// empty if libpng fails.
std::string raw_png(const std::vector<std::uint16_t>& values, int W, int H, int channels, int bit_depth);

} // namespace plenoptic

#endif
