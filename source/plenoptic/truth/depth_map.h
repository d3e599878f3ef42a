// SPDX-License-Identifier: AGPL-3.0-or-later
// The depth map of one render, filled as the image is rendered: storage that grows only with the
// rows actually rendered, and the pacing of the depth a continued render (+C) owes for the pixels
// it does not trace again. No POV-Ray dependency; the renderer's glue computes the depths.

#ifndef PLENOPTIC_DEPTH_MAP_H
#define PLENOPTIC_DEPTH_MAP_H

#include <atomic>
#include <cstddef>
#include <memory>
#include <vector>

namespace plenoptic {

// A rectangle of pixels, bounds inclusive (as POV-Ray's render blocks), top row first.
struct PixelRect {
    int left, top, right, bottom;
};

// Depth per pixel of a width x height image, row-major, top row first. A row is allocated (and
// filled with -1) the first time one of its pixels is set, so a partial render (+SR/+ER) or a
// render stopped early holds only what it rendered; every other pixel reads -1. set() may be
// called from several threads at once for different pixels; reading is for after the render.
class DepthMap {
public:
    DepthMap(int width, int height);
    ~DepthMap();
    DepthMap(const DepthMap&) = delete;
    DepthMap& operator=(const DepthMap&) = delete;

    int width() const { return width_; }
    int height() const { return height_; }
    void set(int column, int row, float depth);
    float at(int column, int row) const;
    // Row `row`, or nullptr when none of its pixels was set.
    const float* row(int row) const;
    std::size_t allocated_rows() const;

private:
    int width_, height_;
    std::unique_ptr<std::atomic<float*>[]> rows_;
};

// One run of pixels of one row; row -1: no run.
struct PixelRun {
    int row, left, right;  // right inclusive
    bool none() const { return row < 0; }
};

// The depth a render owes for pixels it does not trace (a continued render's finished blocks):
// handed out in runs of one row of one block, in step with the traced pixels, so that the work
// is spread over the render (its progress keeps moving, a stop request is seen between runs)
// and every run has been handed out once the last pixel is traced.
class DepthBackfill {
public:
    // untraced: the rectangles of pixels not traced; pixels_to_trace: how many pixels the render
    // does trace.
    DepthBackfill(const std::vector<PixelRect>& untraced, long long pixels_to_trace);

    // Called once per traced pixel: counts it. Then call next_due() until it returns no run.
    void pixel_traced();
    // The next run due at this point of the render, or none (each run is handed out once).
    PixelRun next_due();

    std::size_t runs() const { return std::size_t(total_runs_); }
    // Runs not yet handed out (after the render: pixels whose depth is unknown).
    long long pixels_not_handed_out() const;

private:
    PixelRun run(long long index) const;

    // The runs are the rows of the rectangles in order; run k is found from the running row
    // counts (memory per rectangle, not per row: a continued 20000x20000 render has ~400,000
    // finished blocks of 32 rows).
    std::vector<PixelRect> rects_;
    std::vector<long long> rows_before_;  // rows of the rectangles before each one
    long long total_runs_;
    long long pixels_to_trace_;
    std::atomic<long long> traced_;
    std::atomic<long long> handed_out_;
};

} // namespace plenoptic

#endif
