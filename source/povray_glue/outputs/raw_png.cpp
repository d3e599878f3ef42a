// SPDX-License-Identifier: AGPL-3.0-or-later
// 16-bit PNGs written row by row with libpng (see the header).

#include "povray_glue/outputs/raw_png.h"

#include <csetjmp>

namespace plenoptic {

// libpng reports its errors by longjmp to the setjmp of the call that failed: each method sets
// its own, and nothing with a destructor lives between it and libpng's calls.

PngRowWriter::PngRowWriter(std::FILE* file, int W, int H, int channels, int bit_depth)
    : W_(W), H_(H), channels_(channels), row_(size_t(W > 0 ? W : 0) * (channels > 0 ? channels : 0) * 2)
{
    if (file == nullptr || W <= 0 || H <= 0 || (channels != 1 && channels != 3)) {
        failed_ = true;
        return;
    }
    png_ = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    if (png_ != nullptr)
        info_ = png_create_info_struct(png_);
    if (png_ == nullptr || info_ == nullptr || setjmp(png_jmpbuf(png_))) {
        failed_ = true;
        return;
    }
    png_init_io(png_, file);
    png_set_IHDR(png_, info_, png_uint_32(W), png_uint_32(H), 16, channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_color_8 significant;
    significant.red = significant.green = significant.blue = significant.gray = png_byte(bit_depth);
    significant.alpha = 0;
    png_set_sBIT(png_, info_, &significant);
    png_write_info(png_, info_);
}

PngRowWriter::~PngRowWriter()
{
    if (png_ != nullptr)
        png_destroy_write_struct(&png_, info_ != nullptr ? &info_ : nullptr);
}

bool PngRowWriter::write_row(const std::uint16_t* values)
{
    if (failed_ || rows_ >= H_)
        return false;
    for (size_t k = 0; k < size_t(W_) * channels_; ++k) {
        row_[2 * k] = png_byte(values[k] >> 8);  // PNG is big-endian
        row_[2 * k + 1] = png_byte(values[k] & 0xff);
    }
    if (setjmp(png_jmpbuf(png_))) {
        failed_ = true;
        return false;
    }
    png_write_row(png_, row_.data());
    ++rows_;
    return true;
}

bool PngRowWriter::finish()
{
    if (failed_ || rows_ != H_)
        return false;
    if (setjmp(png_jmpbuf(png_))) {
        failed_ = true;
        return false;
    }
    png_write_end(png_, nullptr);
    return true;
}

} // namespace plenoptic
