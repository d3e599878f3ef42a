// SPDX-License-Identifier: AGPL-3.0-or-later
#include "plenoptic/truth/depth_map.h"

#include <algorithm>

namespace plenoptic {

DepthMap::DepthMap(int width, int height)
    : width_(std::max(width, 0)), height_(std::max(height, 0)), rows_(new std::atomic<float*>[std::size_t(height_)])
{
    for (int j = 0; j < height_; ++j)
        rows_[j].store(nullptr);
}

DepthMap::~DepthMap()
{
    for (int j = 0; j < height_; ++j)
        delete[] rows_[j].load();
}

void DepthMap::set(int column, int row, float depth)
{
    if (column < 0 || column >= width_ || row < 0 || row >= height_)
        return;
    float* line = rows_[row].load(std::memory_order_acquire);
    if (line == nullptr) {
        float* fresh = new float[std::size_t(width_)];
        std::fill(fresh, fresh + width_, -1.0f);
        // Another thread may have allocated the row meanwhile: keep its row, drop ours.
        if (rows_[row].compare_exchange_strong(line, fresh, std::memory_order_acq_rel))
            line = fresh;
        else
            delete[] fresh;
    }
    line[column] = depth;
}

float DepthMap::at(int column, int row) const
{
    const float* line = this->row(row);
    return line == nullptr || column < 0 || column >= width_ ? -1.0f : line[column];
}

const float* DepthMap::row(int row) const
{
    return row < 0 || row >= height_ ? nullptr : rows_[row].load(std::memory_order_acquire);
}

std::size_t DepthMap::allocated_rows() const
{
    std::size_t n = 0;
    for (int j = 0; j < height_; ++j)
        n += rows_[j].load() != nullptr;
    return n;
}

DepthBackfill::DepthBackfill(const std::vector<PixelRect>& untraced, long long pixels_to_trace)
    : total_runs_(0), pixels_to_trace_(std::max(pixels_to_trace, 0LL)), traced_(0), handed_out_(0)
{
    for (const PixelRect& r : untraced) {
        if (r.left > r.right || r.top > r.bottom)
            continue;
        rects_.push_back(r);
        rows_before_.push_back(total_runs_);
        total_runs_ += r.bottom - r.top + 1;
    }
}

PixelRun DepthBackfill::run(long long index) const
{
    // The last rectangle whose first run is at or before `index`.
    const std::size_t k =
        std::size_t(std::upper_bound(rows_before_.begin(), rows_before_.end(), index) - rows_before_.begin()) - 1;
    const PixelRect& r = rects_[k];
    return PixelRun{r.top + int(index - rows_before_[k]), r.left, r.right};
}

void DepthBackfill::pixel_traced()
{
    traced_.fetch_add(1, std::memory_order_relaxed);
}

PixelRun DepthBackfill::next_due()
{
    const long long total = total_runs_;
    const long long traced = traced_.load(std::memory_order_relaxed);
    // Runs due after `traced` of the pixels: the same share of all runs, rounded up, so the
    // first traced pixel starts the work and the last one has every run handed out.
    long long due = total;
    if (traced < pixels_to_trace_)
        due = (long long)((static_cast<long double>(total) * traced + pixels_to_trace_ - 1) / pixels_to_trace_);
    long long next = handed_out_.load(std::memory_order_relaxed);
    while (next < std::min(due, total)) {
        if (handed_out_.compare_exchange_weak(next, next + 1, std::memory_order_relaxed))
            return run(next);
    }
    return PixelRun{-1, 0, -1};
}

long long DepthBackfill::pixels_not_handed_out() const
{
    long long pixels = 0;
    for (long long k = std::min(handed_out_.load(), total_runs_); k < total_runs_; ++k) {
        const PixelRun r = run(k);
        pixels += r.right - r.left + 1;
    }
    return pixels;
}

} // namespace plenoptic
