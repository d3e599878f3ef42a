// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor's raw as a 16-bit PNG (see the header), encoded in memory with libpng.

#include "povray_glue/outputs/raw_png.h"

#include <csetjmp>

#include <png.h>

namespace plenoptic {

namespace {

void append_bytes(png_structp png, png_bytep data, png_size_t length)
{
    static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), length);
}

void no_flush(png_structp) {}

} // namespace

std::string raw_png(const std::vector<std::uint16_t>& values, int W, int H, int channels, int bit_depth)
{
    if (W <= 0 || H <= 0 || (channels != 1 && channels != 3) || values.size() != size_t(W) * H * channels)
        return "";
    // Everything with a destructor is made before setjmp: libpng's errors longjmp back here.
    std::string bytes;
    std::vector<png_byte> row(size_t(W) * channels * 2);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    if (png == nullptr)
        return "";
    png_infop info = png_create_info_struct(png);
    if (info == nullptr || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, info != nullptr ? &info : nullptr);
        return "";
    }
    png_set_write_fn(png, &bytes, append_bytes, no_flush);
    png_set_IHDR(png, info, png_uint_32(W), png_uint_32(H), 16, channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_color_8 significant;
    significant.red = significant.green = significant.blue = significant.gray = png_byte(bit_depth);
    significant.alpha = 0;
    png_set_sBIT(png, info, &significant);
    png_write_info(png, info);
    for (int j = 0; j < H; ++j) {
        const std::uint16_t* source = &values[size_t(j) * W * channels];
        for (size_t k = 0; k < size_t(W) * channels; ++k) {
            row[2 * k] = png_byte(source[k] >> 8);  // PNG is big-endian
            row[2 * k + 1] = png_byte(source[k] & 0xff);
        }
        png_write_row(png, row.data());
    }
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return bytes;
}

} // namespace plenoptic
