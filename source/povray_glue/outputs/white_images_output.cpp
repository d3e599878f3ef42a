// SPDX-License-Identifier: AGPL-3.0-or-later
// The white images output (`white_image`): the camera alone in front of a white diffuser
// (sensor/white_image.h), at its own aperture (<image>.white.png) or at each f-number asked for
// (<image>.white.f<N>.png); with the camera's diffraction; through the read-out when there is one
// (each its own frame of noise), unless noise_free. Listed in the metadata, written or not. Taken
// from the white images' cache when PLENOPTIC_WHITE_IMAGE_CACHE names one and it holds this
// camera's (white_image_cache.h), and stored there when computed.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

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

// The PNG of white image index k (`values`: its grey irradiance per pixel, rows from the top) in
// `png` (empty if libpng failed), and in `scale` what the linear values were divided by. false:
// cancelled.
bool white_png(const PlenopticCamera& optics, const std::vector<float>& values, const CameraParams& params, bool raw, int k,
               CancelQuery cancelled, std::string& png, double& scale)
{
    const int W = optics.sensor.film.width, H = optics.sensor.film.height;
    const SensorChainParams& chain = params.sensor.chain;
    // R, G and B of the grey white image, where they are needed: diffraction differs by colour
    // (the white image is then RGB), and the read-out reads three channels.
    const Diffraction diffraction = diffraction_of(optics, params.diffraction);
    std::vector<float> rgb;
    if (diffraction.applied || raw) {
        rgb.resize(values.size() * 3);
        for (size_t p = 0; p < values.size(); ++p)
            rgb[3 * p] = rgb[3 * p + 1] = rgb[3 * p + 2] = values[p];
    }
    if (diffraction.applied) {
        const std::vector<AiryKernel> kernels = channel_kernels(optics, diffraction);
        if (!convolve_channels(rgb, W, H, 3, kernels.data(), cancelled))
            return false;
    }
    scale = 1;
    if (raw) {
        SensorChainParams frame = chain;
        frame.seed = chain.seed ^ (0x7768697465000000ULL + std::uint64_t(k + 1));  // "white": its own noise
        png = raw_png(sensor_raw(frame, rgb, W, H), W, H, chain.bayer != BayerPattern::None ? 1 : 3, chain.bit_depth);
        return true;
    }
    // Irradiance can exceed 1 (overlap at a microimage's rim, a lens cell's corners): divided by a
    // power of two so that nothing clips, recorded as the entry's scale.
    const std::vector<float>& source = diffraction.applied ? rgb : values;
    float largest = 0;
    for (float v : source)
        largest = std::max(largest, v);
    while (scale < largest && scale < 65536)
        scale *= 2;
    std::vector<std::uint16_t> linear(source.size());
    for (size_t p = 0; p < source.size(); ++p)
        linear[p] = std::uint16_t(std::lround(std::min(1.0, std::max(0.0, source[p] / scale)) * 65535.0));
    png = raw_png(linear, W, H, diffraction.applied ? 3 : 1, 16);
    return true;
}

class WhiteImagesOutput : public Output {
public:
    explicit WhiteImagesOutput(const Render& render) : render_(render), cache_(WhiteImageCache::from_environment()) {}

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
            std::string png;
            double scale = 1;
            const std::string description =
                cache_.enabled() ? white_image_description(optics, params, f_number, k, raw, cache_.executable()) : "";
            CachedWhiteImage cached;
            if (cache_.enabled() && cache_.find(description, &cached)) {
                std::fprintf(stderr, "plenoptic camera: white image %s: the cached one, %s\n", base_name(path).c_str(),
                             cache_.png_path(description).c_str());
                png = cached.png;
                scale = cached.scale;
            } else {
                const std::vector<float> values = white_image(optics, image.cancelled);
                if (values.empty())
                    break;  // cancelled
                if (!white_png(optics, values, params, raw, k, image.cancelled, png, scale))
                    break;  // cancelled
                if (cache_.enabled() && !png.empty()) {
                    cached.png = png;
                    cached.scale = scale;
                    if (cache_.store(description, cached))
                        std::fprintf(stderr, "plenoptic camera: white image %s: computed, and cached as %s\n",
                                     base_name(path).c_str(), cache_.png_path(description).c_str());
                }
            }
            if (!png.empty() && write_file_atomically("white image", path, png)) {
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
        if (image.cancelled())
            std::fprintf(stderr, "plenoptic camera: cancelled: white images not all written.\n");
        return ok;
    }

private:
    const Render& render_;
    const WhiteImageCache cache_;  // PLENOPTIC_WHITE_IMAGE_CACHE's folder, or disabled
    std::vector<WhiteImageFile> written_;  // what the metadata lists
};

} // namespace

std::unique_ptr<Output> start_white_images(const Render& render, const RenderArea&)
{
    if (!render.setup().white_image.given)
        return nullptr;
    return std::unique_ptr<Output>(new WhiteImagesOutput(render));
}

} // namespace plenoptic
