// SPDX-License-Identifier: AGPL-3.0-or-later
// The depth map output (see depth_map_output.h).

#include "povray_glue/outputs/depth_map_output.h"

#include <cstdio>

#include "plenoptic/camera/pixel.h"
#include "povray_glue/outputs/files.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {

namespace {

long long pixels_in(const PixelRect& r)
{
    return r.right < r.left || r.bottom < r.top ? 0 : (long long)(r.right - r.left + 1) * (r.bottom - r.top + 1);
}

long long pixels_traced(const RenderArea& area)
{
    long long owed = 0;
    for (const PixelRect& r : area.untraced)
        owed += pixels_in(r);
    return pixels_in(area.area) - owed;
}

} // namespace

DepthMapOutput::DepthMapOutput(const Render& render, const RenderArea& area)
    : render_(render), map_(render.width(), render.height()), backfill_(area.untraced, pixels_traced(area))
{
}

float DepthMapOutput::depth_of(int column, int row, SceneProbe& scene) const
{
    if (!render_.model().receives_light(column, row))
        return -1.0f;
    return (float)scene.first_hit(render_.model().chief_ray(column, row));
}

void DepthMapOutput::pixel_traced(int column, int row, SceneProbe& scene)
{
    map_.set(column, row, depth_of(column, row, scene));
    // A continued render (+C) owes the depth of the blocks it does not trace: a share of it with
    // each traced pixel, a row of a block at a time, stopping promptly when asked to.
    backfill_.pixel_traced();
    for (PixelRun run = backfill_.next_due(); !run.none(); run = backfill_.next_due()) {
        for (int c = run.left; c <= run.right; c++)
            map_.set(c, run.row, depth_of(c, run.row, scene));
        scene.cooperate();
    }
}

const DepthMap* DepthMapOutput::map_of(const WrittenImage& image) const
{
    const bool same_size = image.picture.width() == render_.width() && image.picture.height() == render_.height();
    return same_size ? &map_ : nullptr;
}

bool DepthMapOutput::write(const WrittenImage& image, SidecarFiles& files)
{
    if (map_of(image) == nullptr)
        return true;
    const long long unknown = backfill_.pixels_not_handed_out();
    if (unknown > 0)
        std::fprintf(stderr, "plenoptic camera: the depth of %lld pixels rendered before the render was "
                             "continued (+C) is unknown: this render traced no pixel that could compute it; "
                             "they read -1 in the depth map.\n", unknown);
    const std::string path = image.beside(".depth.exr");
    // -1 in rows never rendered.
    const int W = map_.width();
    const bool written = write_float_exr(path, "depth map", "Z", W, map_.height(), [&](int j, float* row) {
        const float* rendered = map_.row(j);
        for (int i = 0; i < W; ++i)
            row[i] = rendered != nullptr ? rendered[i] : -1.0f;
        return true;
    });
    if (written)
        files.depth_map = base_name(path);
    return written;
}

std::unique_ptr<Output> start_depth_map(const Render& render, const RenderArea& area)
{
    if (!render.setup().depth_map)
        return nullptr;
    return std::unique_ptr<Output>(new DepthMapOutput(render, area));
}

} // namespace plenoptic
