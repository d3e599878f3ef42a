// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor's raw output: <image>.raw.png, the rendered picture (linear) through the sensor's
// read-out chain (sensor/sensor_chain.h). Wanted when the camera has a read-out.

#include <cstdio>

#include "plenoptic/sensor/sensor_chain.h"
#include "povray_glue/outputs/files.h"
#include "povray_glue/outputs/raw_png.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {

namespace {

class RawOutput : public Output {
public:
    explicit RawOutput(const SensorChainParams& chain) : chain_(chain) {}

    bool write(const WrittenImage& image, SidecarFiles& files) override
    {
        const int W = image.picture.width(), H = image.picture.height();
        const std::vector<float> linear = image.picture.linear_rgb();
        const bool mosaic = chain_.bayer != BayerPattern::None;
        const std::string png = raw_png(sensor_raw(chain_, linear, W, H), W, H, mosaic ? 1 : 3, chain_.bit_depth);
        const std::string path = image.beside(".raw.png");
        if (png.empty()) {
            std::fprintf(stderr, "plenoptic camera: cannot encode the raw %s\n", path.c_str());
            return false;
        }
        if (!write_file_atomically("raw", path, png))
            return false;
        files.raw = base_name(path);
        return true;
    }

private:
    const SensorChainParams chain_;
};

} // namespace

std::unique_ptr<Output> start_raw(const Render& render, const RenderArea&)
{
    const SensorChainParams& chain = render.setup().params.sensor.chain;
    if (!chain.given)
        return nullptr;
    return std::unique_ptr<Output>(new RawOutput(chain));
}

} // namespace plenoptic
