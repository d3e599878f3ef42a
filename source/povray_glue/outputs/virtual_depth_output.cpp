// SPDX-License-Identifier: AGPL-3.0-or-later
// The virtual depth output: <image>.virtual_depth.exr, a focused camera's virtual depth per pixel
// (truth/virtual_depth.h) from the depth map (NaN where it reads -1 or was not rendered). Wanted
// with the depth map when the camera is focused (plenoptic 2.0); stops on Ctrl-C (no file).

#include <cstdio>

#include "plenoptic/truth/virtual_depth.h"
#include "povray_glue/outputs/depth_map_output.h"
#include "povray_glue/outputs/files.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {

namespace {

class VirtualDepthOutput : public Output {
public:
    explicit VirtualDepthOutput(const Render& render) : render_(render) {}

    bool write(const WrittenImage& image, SidecarFiles& files) override
    {
        const DepthMapOutput* depth_output = render_.output<DepthMapOutput>();
        const DepthMap* depth = depth_output != nullptr ? depth_output->map_of(image) : nullptr;
        if (depth == nullptr)
            return true;
        const std::string path = image.beside(".virtual_depth.exr");
        if (write_exr(path, image, *depth)) {
            files.virtual_depth_map = base_name(path);
            return true;
        }
        if (image.cancelled()) {
            std::fprintf(stderr, "plenoptic camera: cancelled: no virtual depth map written (%s).\n", path.c_str());
            return true;
        }
        return false;
    }

private:
    static bool write_exr(const std::string& path, const WrittenImage& image, const DepthMap& depth)
    {
        const PlenopticCamera& model = image.camera;
        const int W = depth.width(), H = depth.height();
        if (size_t(W) * H >= 4000000)
            std::fprintf(stderr, "plenoptic camera: virtual depth of %d x %d pixels\n", W, H);
        return write_float_exr(path, "virtual depth map", "V", W, H, [&](int j, float* row) {
            if (image.cancelled())
                return false;
            const float* rendered = depth.row(j);
            for (int i = 0; i < W; ++i)
                row[i] = pixel_virtual_depth(model, i, j, rendered != nullptr ? rendered[i] : -1.0f);
            return true;
        });
    }

    const Render& render_;
};

} // namespace

std::unique_ptr<Output> start_virtual_depth(const Render& render, const RenderArea&)
{
    if (!render.setup().depth_map || !is_focused_camera(render.model()))
        return nullptr;
    return std::unique_ptr<Output>(new VirtualDepthOutput(render));
}

} // namespace plenoptic
