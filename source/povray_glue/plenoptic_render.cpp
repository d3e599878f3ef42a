// SPDX-License-Identifier: AGPL-3.0-or-later
// The state of one plenoptic render (see plenoptic_render.h).

#include "povray_glue/plenoptic_render.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "backend/frame.h"
#include "backend/math/vector.h"
#include "backend/scene/camera.h"

#include "base/povdebug.h"

namespace plenoptic {

namespace {

bool is_orthonormal(const CameraFrame& frame)
{
    const double* axes[3] = {frame.right, frame.up, frame.direction};
    for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) {
            const double dot = axes[a][0] * axes[b][0] + axes[a][1] * axes[b][1] + axes[a][2] * axes[b][2];
            if (std::fabs(dot - (a == b ? 1.0 : 0.0)) > 1e-12)
                return false;
        }
    return true;
}

long long pixels_in(const PixelRect& r)
{
    return r.right < r.left || r.bottom < r.top ? 0 : (long long)(r.right - r.left + 1) * (r.bottom - r.top + 1);
}

std::mutex published_mutex;
std::shared_ptr<Render> published;

} // namespace

Render::Render(std::shared_ptr<const CameraSetup> setup, const CameraFrame& frame, int width, int height,
               PixelRect area, const std::vector<PixelRect>& untraced)
    : setup_(std::move(setup)), model_(with_film(setup_->model, width, height)), frame_(frame),
      frame_orthonormal_(is_orthonormal(frame)), width_(width),
      height_(height), continued_(!untraced.empty())
{
    if (setup_->depth_map) {
        depth_.reset(new DepthMap(width, height));
        long long owed = 0;
        for (const PixelRect& r : untraced)
            owed += pixels_in(r);
        backfill_.reset(new DepthBackfill(untraced, pixels_in(area) - owed));
    }
}

void publish_render(std::shared_ptr<Render> render)
{
    std::lock_guard<std::mutex> lock(published_mutex);
    published = std::move(render);
}

std::shared_ptr<Render> published_render()
{
    std::lock_guard<std::mutex> lock(published_mutex);
    return published;
}

std::shared_ptr<Render> take_published_render()
{
    std::lock_guard<std::mutex> lock(published_mutex);
    std::shared_ptr<Render> render;
    render.swap(published);
    return render;
}

} // namespace plenoptic

namespace pov {

std::shared_ptr<plenoptic::Render> Plenoptic_Start_Render(
    const Camera& camera, unsigned int width, unsigned int height, const pov_base::POVRect& area, unsigned int block_size,
    const std::vector<std::pair<unsigned int, unsigned int> >& finished_blocks)
{
    plenoptic::CameraFrame frame;
    Vector3d right(camera.Right), up(camera.Up), direction(camera.Direction);
    right.normalize();
    up.normalize();
    direction.normalize();
    // The optics frame's origin: the scene's location is a real lens's front vertex, the frame's
    // origin its rear vertex, the lens's length behind it.
    const double behind_units = camera.Plenoptic->model.lens_length_mm / camera.Plenoptic->model.mm_per_unit;
    for (int i = 0; i < 3; i++) {
        frame.location[i] = camera.Location[i] - behind_units * direction[i];
        frame.right[i] = right[i];
        frame.up[i] = up[i];
        frame.direction[i] = direction[i];
    }
    // The blocks as POV-Ray's ViewData::GetNextRectangle cuts them from the render area.
    std::vector<plenoptic::PixelRect> untraced;
    for (const std::pair<unsigned int, unsigned int>& block : finished_blocks) {
        const unsigned int left = area.left + block.first * block_size, top = area.top + block.second * block_size;
        if (left > area.right || top > area.bottom)
            continue;
        untraced.push_back(plenoptic::PixelRect{int(left), int(top), int(std::min(left + block_size - 1, area.right)),
                                                int(std::min(top + block_size - 1, area.bottom))});
    }
    const plenoptic::PixelRect whole{int(area.left), int(area.top), int(area.right), int(area.bottom)};
    std::shared_ptr<plenoptic::Render> render =
        std::make_shared<plenoptic::Render>(camera.Plenoptic, frame, int(width), int(height), whole, untraced);
    plenoptic::publish_render(render);
    return render;
}

} // namespace pov
