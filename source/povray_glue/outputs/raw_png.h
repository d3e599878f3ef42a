// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor's raw and the white images as 16-bit PNGs: grey for a Bayer mosaic (or a grey white
// image), RGB otherwise, the values the DN themselves (no scaling), with an sBIT chunk giving the
// sensor's bit depth. Written row by row as the rows are made, so a picture of any size needs
// the memory of one row here.

#ifndef POVRAY_GLUE_OUTPUTS_RAW_PNG_H
#define POVRAY_GLUE_OUTPUTS_RAW_PNG_H

#include <cstdint>
#include <cstdio>
#include <vector>

#include <png.h>

namespace plenoptic {

class PngRowWriter {
public:
    // A PNG of W x H pixels of `channels` (1 or 3) values each, to `file` (open for writing).
    PngRowWriter(std::FILE* file, int W, int H, int channels, int bit_depth);
    ~PngRowWriter();
    PngRowWriter(const PngRowWriter&) = delete;
    PngRowWriter& operator=(const PngRowWriter&) = delete;

    // The next row from the top (W channels values); false once libpng has failed.
    bool write_row(const std::uint16_t* values);
    // After the H rows: the file's end; false if libpng failed at any point or rows are missing.
    bool finish();

private:
    png_structp png_ = nullptr;
    png_infop info_ = nullptr;
    int W_, H_, channels_, rows_ = 0;
    bool failed_ = false;
    std::vector<png_byte> row_;  // one row, big-endian
};

} // namespace plenoptic

#endif
