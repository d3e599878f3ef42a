// SPDX-License-Identifier: AGPL-3.0-or-later
// The white images output (`white_image`): the camera alone in front of a white diffuser
// (sensor/white_image.h), at its own aperture (<image>.white.png) or at each f-number asked for
// (<image>.white.f<N>.png); with the camera's diffraction; through the read-out when there is one
// (each its own frame of noise), unless noise_free. Listed in the metadata, written or not. Taken
// from the white images' cache when PLENOPTIC_WHITE_IMAGE_CACHE names one and it holds this
// camera's (white_image_cache.h), and stored there when computed.

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>

#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/sensor/sensor_chain.h"
#include "plenoptic/sensor/white_image.h"
#include "povray_glue/outputs/files.h"
#include "povray_glue/outputs/raw_png.h"
#include "povray_glue/outputs/render.h"
#include "povray_glue/outputs/white_image_cache.h"

namespace plenoptic {

namespace {

// The same camera, film included, at f-number N: the one place the white images get it from.
PlenopticCamera camera_at_f_number(const PlenopticCamera& camera, double f_number) { return with_f_number(camera, f_number); }

// Rows of the white image computed at once where no convolution sets the bands.
const int kWhiteBandRows = 64;

// White image index k of `optics` written to `path` as a PNG, band by band of rows (memory: a few
// bands, whatever the sensor's size): the grey irradiance per pixel (`kept`, W x H values from the
// top, when the render kept them, else white_image_rows); with
// diffraction, as R, G and B (diffraction differs by colour) convolved band by band; through the
// read-out when `raw`, else linear, divided by `scale`. false: cancelled (nothing written, no
// message) or a file could not be written (with a message).
bool write_white_png(const PlenopticCamera& optics, const CameraParams& params, bool raw, int k, const std::string& path,
                     CancelQuery cancelled, const float* kept, double& scale)
{
    const int W = optics.sensor.film.width, H = optics.sensor.film.height;
    const SensorChainParams& chain = params.sensor.chain;
    const Diffraction diffraction = diffraction_of(optics, params.diffraction);
    // The values' channels: R, G and B of the grey white image where they are needed (diffraction,
    // or the read-out, which reads three channels), else grey.
    const int channels = diffraction.applied || raw ? 3 : 1;

    // Minutes for a large sensor (it is traced as the picture is): say how far, every tenth.
    const bool large = size_t(W) * H >= 4000000 && kept == nullptr;
    if (large)
        std::fprintf(stderr, "plenoptic camera: white image %s: %d x %d pixels\n", base_name(path).c_str(), W, H);
    int tenths = 0;
    // The white image's rows, from the top: grey, then R = G = B when three channels.
    std::vector<float> grey;
    const RowReader white_rows = [&](int first, int count, float* to) {
        grey.resize(size_t(count) * W);
        if (kept != nullptr)
            std::copy(kept + size_t(first) * W, kept + size_t(first + count) * W, grey.begin());
        else if (!white_image_rows(optics, first, count, grey.data(), cancelled))
            return false;
        if (large && (first + count) * 10 >= (tenths + 1) * H) {
            tenths = (first + count) * 10 / H;
            std::fprintf(stderr, "plenoptic camera: white image %s: %d of %d rows\n", base_name(path).c_str(), first + count, H);
        }
        for (size_t p = 0; p < grey.size(); ++p)
            for (int c = 0; c < channels; ++c)
                to[p * size_t(channels) + size_t(c)] = grey[p];
        return true;
    };
    // Every row of the finished values (after diffraction), from the top, to `sink`.
    auto produce = [&](const RowWriter& sink) {
        if (diffraction.applied) {
            const std::vector<AiryKernel> kernels = channel_kernels(optics, diffraction);
            return convolve_rows(W, H, 3, kernels.data(), white_rows, sink, cancelled);
        }
        std::vector<float> band(size_t(std::min(kWhiteBandRows, H)) * W * channels);
        for (int first = 0; first < H; first += kWhiteBandRows) {
            const int rows = std::min(kWhiteBandRows, H - first);
            if (!white_rows(first, rows, band.data()) || !sink(first, rows, band.data()))
                return false;
        }
        return true;
    };

    scale = 1;
    if (raw) {
        SensorChainParams frame = chain;
        frame.seed = chain.seed ^ (0x7768697465000000ULL + std::uint64_t(k + 1));  // "white": its own noise
        const int out_channels = chain.bayer != BayerPattern::None ? 1 : 3;
        return write_file_streamed("white image", path, [&](std::FILE* file) -> Fill {
            PngRowWriter png(file, W, H, out_channels, chain.bit_depth);
            std::vector<std::uint16_t> values;
            bool failed = false;
            const RowWriter read_out = [&](int first, int count, const float* rgb) {
                values.resize(size_t(count) * W * out_channels);
                sensor_raw_rows(frame, rgb, W, first, count, values.data());
                for (int r = 0; r < count; ++r)
                    if (!png.write_row(&values[size_t(r) * W * out_channels])) {
                        failed = true;
                        return false;
                    }
                return true;
            };
            if (!produce(read_out))
                return failed ? Fill::Failed : Fill::Abandoned;
            return png.finish() ? Fill::Complete : Fill::Failed;
        });
    }
    // Irradiance can exceed 1 (overlap at a microimage's rim, a lens cell's corners): divided by a
    // power of two so that nothing clips, recorded as the entry's scale. The largest value is known
    // only at the end, so the values wait in a scratch file beside it (not in memory) for the second
    // pass.
    std::FILE* values = scratch_file_beside(path);
    if (values == nullptr) {
        std::fprintf(stderr, "plenoptic camera: cannot write white image %s: no scratch file beside it (%s)\n",
                     path.c_str(), std::strerror(errno));
        return false;
    }
    float largest = 0;
    bool spilled = true;
    const RowWriter keep = [&](int, int count, const float* from) {
        const size_t n = size_t(count) * W * channels;
        for (size_t p = 0; p < n; ++p)
            largest = std::max(largest, from[p]);
        spilled = spilled && std::fwrite(from, sizeof(float), n, values) == n;
        return spilled;
    };
    bool written = false;
    if (produce(keep)) {
        while (scale < largest && scale < 65536)
            scale *= 2;
        std::rewind(values);
        written = write_file_streamed("white image", path, [&](std::FILE* file) -> Fill {
            PngRowWriter png(file, W, H, channels, 16);
            std::vector<float> row(size_t(W) * channels);
            std::vector<std::uint16_t> linear(row.size());
            for (int j = 0; j < H; ++j) {
                if (std::fread(row.data(), sizeof(float), row.size(), values) != row.size())
                    return Fill::Failed;
                for (size_t p = 0; p < row.size(); ++p)
                    linear[p] = std::uint16_t(std::lround(std::min(1.0, std::max(0.0, row[p] / scale)) * 65535.0));
                if (!png.write_row(linear.data()))
                    return Fill::Failed;
            }
            return png.finish() ? Fill::Complete : Fill::Failed;
        });
    } else if (!spilled) {
        std::fprintf(stderr, "plenoptic camera: cannot write white image %s: its temporary file: %s\n", path.c_str(),
                     std::strerror(errno));
    }
    std::fclose(values);
    return written;
}

// Whether `area` is the whole of `camera`'s film, every block traced (no +SR/+ER, no +C).
bool whole_render(const PlenopticCamera& camera, const RenderArea& area)
{
    const PixelRect& a = area.area;
    return area.untraced.empty() && a.left == 0 && a.top == 0 && a.right == camera.sensor.film.width - 1 &&
           a.bottom == camera.sensor.film.height - 1;
}

class WhiteImagesOutput : public Output {
public:
    WhiteImagesOutput(const Render& render, const RenderArea& area)
        : render_(render), cache_(WhiteImageCache::from_environment())
    {
        // The white image at the camera's own aperture is what the render's own samples give in a
        // world of radiance 1 (shade_pixel_and_white), so a whole render with a fixed sample count
        // keeps it as it goes (a float a pixel) instead of tracing the camera a second time; unless
        // the cache holds it already.
        const WhiteImageRequest& white = render.setup().white_image;
        const PlenopticCamera& model = render.model();
        if (!white.f_numbers.empty() || model.sampling.adaptive || !whole_render(model, area))
            return;
        if (cache_.enabled() && cache_.holds(description(model, 0, model.f_number())))
            return;
        kept_.assign(size_t(model.sensor.film.width) * model.sensor.film.height, std::numeric_limits<float>::quiet_NaN());
    }

    bool keeps_white() const override { return !kept_.empty(); }
    void pixel_white(int column, int row, double white) override
    {
        kept_[size_t(row) * render_.width() + size_t(column)] = float(white);
    }

    bool write(const WrittenImage& image, SidecarFiles& files) override
    {
        const WhiteImageRequest& white = render_.setup().white_image;
        const CameraParams& params = render_.setup().params;
        const PlenopticCamera& model = image.camera;
        bool ok = true;
        written_.clear();
        files.white_images = &written_;
        const int count = white.f_numbers.empty() ? 1 : int(white.f_numbers.size());
        for (int k = 0; k < count && !image.cancelled(); ++k) {
            const bool own = white.f_numbers.empty();
            const double f_number = own ? model.f_number() : white.f_numbers[size_t(k)];
            std::unique_ptr<PlenopticCamera> other;
            if (!own)
                other.reset(new PlenopticCamera(camera_at_f_number(model, f_number)));
            const PlenopticCamera& optics = own ? model : *other;
            const bool raw = params.sensor.chain.given && !white.noise_free;
            const std::string path = image.beside(white_image_suffix(white, k));
            double scale = 1;
            const std::string description = cache_.enabled() ? this->description(optics, k, f_number) : "";
            bool written = false;
            if (cache_.enabled() && cache_.copy_out(description, path, &scale)) {
                std::fprintf(stderr, "plenoptic camera: white image %s: the cached one, %s\n", base_name(path).c_str(),
                             cache_.png_path(description).c_str());
                written = true;
            } else {
                const float* kept = own ? kept_white(image) : nullptr;
                if (kept != nullptr)
                    std::fprintf(stderr, "plenoptic camera: white image %s: from the render's own samples\n",
                                 base_name(path).c_str());
                written = write_white_png(optics, params, raw, k, path, image.cancelled, kept, scale);
                if (image.cancelled())
                    break;
                if (written && cache_.enabled() && cache_.store(description, path, scale))
                    std::fprintf(stderr, "plenoptic camera: white image %s: computed, and cached as %s\n",
                                 base_name(path).c_str(), cache_.png_path(description).c_str());
            }
            if (written) {
                WhiteImageFile file;
                file.file = base_name(path);
                file.f_number = f_number;
                file.raw = raw;
                file.scale = scale;
                written_.push_back(file);
            } else {
                ok = false;
            }
        }
        std::vector<float>().swap(kept_);  // its memory back for the outputs after this one
        if (image.cancelled())
            std::fprintf(stderr, "plenoptic camera: cancelled: white images not all written.\n");
        return ok;
    }

private:
    // The cache's description of white image k (at f-number N) of `optics`.
    std::string description(const PlenopticCamera& optics, int k, double f_number) const
    {
        const CameraParams& params = render_.setup().params;
        const bool raw = params.sensor.chain.given && !render_.setup().white_image.noise_free;
        return white_image_description(optics, params, f_number, k, raw, cache_.executable());
    }

    // The values the render kept, when it kept every pixel of `image`'s film; else nullptr.
    const float* kept_white(const WrittenImage& image) const
    {
        const Film& film = image.camera.sensor.film;
        if (kept_.empty() || film.width != render_.width() || film.height != render_.height())
            return nullptr;
        for (float v : kept_)
            if (std::isnan(v))
                return nullptr;
        return kept_.data();
    }

    const Render& render_;
    const WhiteImageCache cache_;  // PLENOPTIC_WHITE_IMAGE_CACHE's folder, or disabled
    std::vector<float> kept_;      // the render's own white values (W x H from the top), or empty
    std::vector<WhiteImageFile> written_;  // what the metadata lists
};

} // namespace

std::unique_ptr<Output> start_white_images(const Render& render, const RenderArea& area)
{
    if (!render.setup().white_image.given)
        return nullptr;
    return std::unique_ptr<Output>(new WhiteImagesOutput(render, area));
}

} // namespace plenoptic
