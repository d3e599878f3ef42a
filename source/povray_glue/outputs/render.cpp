// SPDX-License-Identifier: AGPL-3.0-or-later
// The state of one plenoptic render and its hand-over to the front end (see render.h).

#include "povray_glue/outputs/render.h"

#include <cmath>
#include <map>
#include <mutex>

namespace plenoptic {

namespace {

bool is_orthonormal(const CameraFrame& frame)
{
    const Vec3 axes[3] = {frame.right, frame.up, frame.direction};
    for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) {
            if (std::fabs(dot(axes[a], axes[b]) - (a == b ? 1.0 : 0.0)) > 1e-12)
                return false;
        }
    return true;
}

std::mutex published_mutex;
std::map<int, std::weak_ptr<Render> > published;  // by view

} // namespace

Render::Render(std::shared_ptr<const CameraSetup> setup, const CameraFrame& frame, int width, int height,
               const RenderArea& area, const std::vector<OutputKind>& kinds)
    : setup_(std::move(setup)), model_(with_film(setup_->model, width, height)), frame_(frame),
      frame_orthonormal_(is_orthonormal(frame)), continued_(!area.untraced.empty())
{
    for (const OutputKind& kind : kinds) {
        std::unique_ptr<Output> output = kind.start(*this, area);
        if (!output)
            continue;
        if (output->traces_pixels())
            pixel_outputs_.push_back(output.get());
        if (output->keeps_white() && white_output_ == nullptr)
            white_output_ = output.get();
        outputs_.push_back(std::move(output));
        names_.push_back(kind.name);
    }
}

Render::~Render() {}

std::vector<std::string> Render::output_names() const
{
    return std::vector<std::string>(names_.begin(), names_.end());
}

void publish_render(int view, const std::shared_ptr<Render>& render)
{
    std::lock_guard<std::mutex> lock(published_mutex);
    // Views closed since (their renders gone) leave the table.
    for (std::map<int, std::weak_ptr<Render> >::iterator it = published.begin(); it != published.end();)
        it = it->second.expired() ? published.erase(it) : std::next(it);
    published[view] = render;
}

std::shared_ptr<Render> published_render(int view)
{
    std::lock_guard<std::mutex> lock(published_mutex);
    const std::map<int, std::weak_ptr<Render> >::const_iterator it = published.find(view);
    return it == published.end() ? std::shared_ptr<Render>() : it->second.lock();
}

std::shared_ptr<Render> take_published_render(int view)
{
    std::lock_guard<std::mutex> lock(published_mutex);
    const std::map<int, std::weak_ptr<Render> >::iterator it = published.find(view);
    if (it == published.end())
        return std::shared_ptr<Render>();
    const std::shared_ptr<Render> render = it->second.lock();
    published.erase(it);
    return render;
}

} // namespace plenoptic
