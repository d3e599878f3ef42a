// SPDX-License-Identifier: AGPL-3.0-or-later
// White images: what the camera records of a uniform white diffuser in front
// of the main lens, the calibration image every decoder starts from. Computed from the camera
// alone: every ray that passes the optics brings radiance 1, so no scene ray is traced; the pixel
// loop is the render's own (shade_pixel), with its samples, vignetting and overlap, so a white
// image equals a render of a white world.

#ifndef PLENOPTIC_WHITE_IMAGE_H
#define PLENOPTIC_WHITE_IMAGE_H

#include <functional>
#include <string>
#include <vector>

#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// `white_image [f_numbers <N1, N2, ...>] [noise_free]` as the parser fills it.
struct WhiteImageRequest {
    bool given = false;
    std::vector<double> f_numbers;  // empty: the camera's own aperture only
    bool noise_free = false;        // with a sensor read-out: the linear picture, not the raw
};

// The most f-numbers one request may list.
const int kMaxWhiteImages = 16;

// "" when the request suits the camera (f_numbers need a main lens with an aperture: thin_lens,
// thick_lens or a prescription), else the message. Ends with check_white_image_f_numbers.
std::string check_white_image(const WhiteImageRequest& request, const CameraParams& params);

// The part of check_white_image about the values: each f-number listed once (each names its own
// file), and each one the camera can be given (as `f_number N` would be checked: a real lens must
// be able to deliver it with its stop limiting the axial beam).
std::string check_white_image_f_numbers(const WhiteImageRequest& request, const CameraParams& params);

// "" unless an f-number is listed twice (then the message: a refusal, since each names its file).
std::string repeated_white_f_number(const WhiteImageRequest& request);

// The W x H white image of `model`, rows from the top (pixel (i, j) at j W + i): each pixel's value
// in a world of radiance 1. Rows are shared among `threads` threads (0: every hardware thread); the
// result does not depend on their number. Returns an empty vector when `cancelled` says so.
std::vector<float> white_image(const PlenopticCamera& model, const std::function<bool()>& cancelled, int threads = 0);

// Rows first_row .. first_row + rows - 1 of the same white image into `out` (rows W values), equal
// to white_image's; false (the rows unfinished) when `cancelled` says so.
bool white_image_rows(const PlenopticCamera& model, int first_row, int rows, float* out, const std::function<bool()>& cancelled,
                      int threads = 0);

// What replaces the image's extension for f-number index k of a request: ".white.png" for the
// camera's own aperture, ".white.f<N>.png" for f_numbers (N shortest: f2, f5.6).
std::string white_image_suffix(const WhiteImageRequest& request, int k);

} // namespace plenoptic

#endif
