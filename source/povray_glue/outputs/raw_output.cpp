// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor's raw output: <image>.raw.png, the rendered picture (linear) through the sensor's
// read-out chain (sensor/sensor_chain.h). Wanted when the camera has a read-out. Made and written
// band by band of rows (memory: a band, whatever the picture's size).

#include <algorithm>
#include <cstdio>

#include "plenoptic/sensor/sensor_chain.h"
#include "povray_glue/outputs/files.h"
#include "povray_glue/outputs/raw_png.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {

namespace {

// Rows read out at once: enough for every thread to have several.
const int kRawBandRows = 64;

class RawOutput : public Output {
public:
    explicit RawOutput(const SensorChainParams& chain) : chain_(chain) {}

    bool write(const WrittenImage& image, SidecarFiles& files) override
    {
        const int W = image.picture.width(), H = image.picture.height();
        const int channels = chain_.bayer != BayerPattern::None ? 1 : 3;
        const std::string path = image.beside(".raw.png");
        if (size_t(W) * H >= 4000000)
            std::fprintf(stderr, "plenoptic camera: raw %s: reading out %d x %d pixels\n", base_name(path).c_str(), W, H);
        const bool written = write_file_streamed("raw", path, [&](std::FILE* file) -> Fill {
            PngRowWriter png(file, W, H, channels, chain_.bit_depth);
            std::vector<float> linear(size_t(std::min(kRawBandRows, H)) * W * 3);
            std::vector<std::uint16_t> raw(size_t(std::min(kRawBandRows, H)) * W * channels);
            for (int first = 0; first < H; first += kRawBandRows) {
                const int rows = std::min(kRawBandRows, H - first);
                image.picture.read_rows(first, rows, linear.data());
                sensor_raw_rows(chain_, linear.data(), W, first, rows, raw.data());
                for (int r = 0; r < rows; ++r)
                    if (!png.write_row(&raw[size_t(r) * W * channels]))
                        return Fill::Failed;
            }
            return png.finish() ? Fill::Complete : Fill::Failed;
        });
        if (!written)
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
