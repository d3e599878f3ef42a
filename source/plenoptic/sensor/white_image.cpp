// SPDX-License-Identifier: AGPL-3.0-or-later
// White images (see the header).

#include "plenoptic/sensor/white_image.h"

#include <algorithm>
#include <atomic>

#include "plenoptic/camera/pixel.h"
#include "plenoptic/core/threads.h"

namespace plenoptic {

std::string check_white_image(const WhiteImageRequest& request, const CameraParams& params)
{
    if (request.f_numbers.empty())
        return "";
    if (int(request.f_numbers.size()) > kMaxWhiteImages)
        return "white_image: f_numbers lists at most " + format_number(kMaxWhiteImages) + " f-numbers, got " +
               format_number(double(request.f_numbers.size()));
    if (!has_sized_aperture(params.main))
        return "white_image: f_numbers needs a main lens with an aperture (thin_lens, thick_lens, lens_file or "
               "prescription { }); this camera has " +
               std::string(is_pinhole(params.main) ? "a pinhole main lens" : "no main lens");
    return check_white_image_f_numbers(request, params);
}

std::string check_white_image_f_numbers(const WhiteImageRequest& request, const CameraParams& params)
{
    const std::string repeated = repeated_white_f_number(request);
    if (!repeated.empty())
        return repeated;
    for (size_t k = 0; k < request.f_numbers.size(); ++k) {
        const double n = request.f_numbers[k];
        const std::string message = check_f_number(n);
        if (!message.empty())
            return "white_image f_numbers: " + message;
        const std::string camera = check_camera(at_f_number(params, n));
        if (!camera.empty())
            return "white_image f_numbers " + format_number(n) + ": " + camera;
    }
    return "";
}

std::string repeated_white_f_number(const WhiteImageRequest& request)
{
    for (size_t k = 0; k < request.f_numbers.size(); ++k)
        for (size_t j = 0; j < k; ++j)
            if (request.f_numbers[j] == request.f_numbers[k])
                return "white_image f_numbers lists " + format_number(request.f_numbers[k]) + " twice (values " +
                       std::to_string(j + 1) + " and " + std::to_string(k + 1) + "); each f-number names its own file (" +
                       white_image_suffix(request, int(k)) + "): list each once";
    return "";
}

bool white_image_rows(const PlenopticCamera& model, int first_row, int rows, float* out, const std::function<bool()>& cancelled,
                      int threads)
{
    const int W = model.sensor.film.width;
    std::atomic<int> next_row(0);
    std::atomic<bool> stop(false);
    auto shade_row = [&](int r) {
        for (int i = 0; i < W; ++i)
            out[size_t(r) * W + i] =
                float(shade_pixel(model, i, first_row + r, [](const OpticsRay&) { return Rgbt{1, 1, 1, 1}; }).r);
    };
    // The calling thread (t = 0) looks at `cancelled` between rows.
    run_on_threads(thread_count(threads, std::size_t(std::max(rows, 0))), [&](int t) {
        for (int r = next_row++; r < rows && !stop; r = next_row++) {
            if (t == 0 && cancelled && cancelled()) {
                stop = true;
                break;
            }
            shade_row(r);
        }
    });
    return !stop;
}

std::vector<float> white_image(const PlenopticCamera& model, const std::function<bool()>& cancelled, int threads)
{
    const int W = model.sensor.film.width, H = model.sensor.film.height;
    std::vector<float> out(size_t(std::max(0, W)) * std::max(0, H), 0.0f);
    if (W > 0 && H > 0 && !white_image_rows(model, 0, H, out.data(), cancelled, threads))
        out.clear();
    return out;
}

std::string white_image_suffix(const WhiteImageRequest& request, int k)
{
    if (request.f_numbers.empty())
        return ".white.png";
    return ".white.f" + format_number(request.f_numbers[size_t(k)]) + ".png";
}

} // namespace plenoptic
