// SPDX-License-Identifier: AGPL-3.0-or-later
// The depth map is filled as the image is rendered. Its storage grows with the
// rows rendered (a partial render holds only its region), and the depth a continued render owes
// for the blocks it does not trace is handed out in step with the render, all of it by the end.

#include <gtest/gtest.h>

#include <set>
#include <thread>
#include <utility>

#include "plenoptic/truth/depth_map.h"

namespace plenoptic {
namespace {

TEST(DepthMap, NothingIsAllocatedUntilARowIsRendered)
{
    // 20000 x 20000: 1.6 GB as one buffer; here only the row pointers until something is set.
    DepthMap depth(20000, 20000);
    EXPECT_EQ(depth.allocated_rows(), 0u);
    EXPECT_EQ(depth.at(123, 4567), -1.0f);
    EXPECT_EQ(depth.row(4567), nullptr);
    depth.set(10, 4567, 2.5f);
    EXPECT_EQ(depth.allocated_rows(), 1u);
    EXPECT_EQ(depth.at(10, 4567), 2.5f);
    EXPECT_EQ(depth.at(11, 4567), -1.0f);  // the rest of a new row reads "not rendered"
    EXPECT_EQ(depth.at(10, 4568), -1.0f);
}

TEST(DepthMap, OutOfRangePixelsAreIgnored)
{
    DepthMap depth(4, 3);
    depth.set(-1, 0, 1.0f);
    depth.set(4, 0, 1.0f);
    depth.set(0, 3, 1.0f);
    depth.set(0, -1, 1.0f);
    EXPECT_EQ(depth.allocated_rows(), 0u);
    EXPECT_EQ(depth.at(4, 0), -1.0f);
}

TEST(DepthMap, ThreadsSettingPixelsOfTheSameRowsKeepEveryValue)
{
    const int W = 257, H = 64;
    DepthMap depth(W, H);
    // Two threads interleave by column over every row, so both race to allocate each row.
    auto fill = [&](int parity) {
        for (int j = 0; j < H; ++j)
            for (int i = parity; i < W; i += 2)
                depth.set(i, j, float(j * W + i));
    };
    std::thread a(fill, 0), b(fill, 1);
    a.join();
    b.join();
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            ASSERT_EQ(depth.at(i, j), float(j * W + i)) << i << ", " << j;
    EXPECT_EQ(depth.allocated_rows(), size_t(H));
}

// Every pixel of the rectangles, each once, as the runs hand them out.
std::multiset<std::pair<int, int>> pixels_of(const std::vector<PixelRun>& runs)
{
    std::multiset<std::pair<int, int>> pixels;
    for (const PixelRun& r : runs)
        for (int i = r.left; i <= r.right; ++i)
            pixels.insert({i, r.row});
    return pixels;
}

TEST(DepthBackfill, HandsOutEveryUntracedPixelOnceByTheLastTracedPixel)
{
    // A continued 100 x 60 render: blocks of 32 already done, 4000 pixels left to trace.
    const std::vector<PixelRect> done = {{0, 0, 31, 31}, {32, 0, 63, 31}, {64, 0, 99, 31}, {0, 32, 31, 59}};
    long long untraced = 0;
    for (const PixelRect& r : done)
        untraced += (long long)(r.right - r.left + 1) * (r.bottom - r.top + 1);
    const long long to_trace = 100 * 60 - untraced;
    DepthBackfill backfill(done, to_trace);
    EXPECT_EQ(backfill.runs(), 32u + 32u + 32u + 28u);
    std::vector<PixelRun> handed;
    long long most_in_one_pixel = 0;
    for (long long p = 0; p < to_trace; ++p) {
        backfill.pixel_traced();
        long long here = 0;
        for (PixelRun run = backfill.next_due(); !run.none(); run = backfill.next_due()) {
            handed.push_back(run);
            here += run.right - run.left + 1;
        }
        most_in_one_pixel = std::max(most_in_one_pixel, here);
        // In step: after p + 1 of the traced pixels, the share (p + 1) / to_trace of the runs.
        const double share = double(handed.size()) / backfill.runs();
        ASSERT_GE(share, double(p + 1) / to_trace - 1e-12);
        ASSERT_LE(share, double(p + 1) / to_trace + 1.0 / backfill.runs() + 1e-12);
    }
    EXPECT_EQ(backfill.pixels_not_handed_out(), 0);
    // Each untraced pixel exactly once.
    const auto pixels = pixels_of(handed);
    EXPECT_EQ((long long)pixels.size(), untraced);
    std::multiset<std::pair<int, int>> want;
    for (const PixelRect& r : done)
        for (int j = r.top; j <= r.bottom; ++j)
            for (int i = r.left; i <= r.right; ++i)
                want.insert({i, j});
    EXPECT_EQ(pixels, want);
    // Spread out: no traced pixel carries more than one run (at most a block's width).
    EXPECT_LE(most_in_one_pixel, 36);
}

TEST(DepthBackfill, RunsAreTheRowsOfTheRectanglesInOrder)
{
    // Rectangles of different heights (one empty, skipped), handed out all at once (one pixel
    // left to trace): every row of each, in order.
    const std::vector<PixelRect> done = {{0, 0, 31, 2}, {5, 10, 4, 20}, {32, 7, 40, 7}, {100, 50, 131, 53}};
    DepthBackfill backfill(done, 1);
    EXPECT_EQ(backfill.runs(), 3u + 1u + 4u);
    backfill.pixel_traced();
    std::vector<PixelRun> got;
    for (PixelRun run = backfill.next_due(); !run.none(); run = backfill.next_due())
        got.push_back(run);
    const std::vector<PixelRun> want = {{0, 0, 31}, {1, 0, 31}, {2, 0, 31}, {7, 32, 40},
                                        {50, 100, 131}, {51, 100, 131}, {52, 100, 131}, {53, 100, 131}};
    ASSERT_EQ(got.size(), want.size());
    for (size_t k = 0; k < want.size(); ++k) {
        EXPECT_EQ(got[k].row, want[k].row) << k;
        EXPECT_EQ(got[k].left, want[k].left) << k;
        EXPECT_EQ(got[k].right, want[k].right) << k;
    }
}

TEST(DepthBackfill, FewPixelsLeftCarryTheWholeBackfillBetweenThem)
{
    const std::vector<PixelRect> done = {{0, 0, 9, 99}};
    DepthBackfill backfill(done, 3);
    size_t runs = 0;
    for (int p = 0; p < 3; ++p) {
        backfill.pixel_traced();
        for (PixelRun run = backfill.next_due(); !run.none(); run = backfill.next_due())
            ++runs;
    }
    EXPECT_EQ(runs, 100u);
    EXPECT_EQ(backfill.pixels_not_handed_out(), 0);
    EXPECT_TRUE(backfill.next_due().none());
}

TEST(DepthBackfill, NothingToTraceLeavesTheBackfillUnhandedAndSaysHowMuch)
{
    DepthBackfill backfill({{0, 0, 9, 9}, {10, 0, 14, 1}}, 0);
    EXPECT_EQ(backfill.pixels_not_handed_out(), 100 + 10);
}

TEST(DepthBackfill, NoUntracedPixelsNoRuns)
{
    DepthBackfill backfill({}, 1000);
    backfill.pixel_traced();
    EXPECT_TRUE(backfill.next_due().none());
    EXPECT_EQ(backfill.pixels_not_handed_out(), 0);
}

TEST(DepthBackfill, ThreadsNeverGetTheSameRun)
{
    std::vector<PixelRect> done;
    for (int b = 0; b < 50; ++b)
        done.push_back(PixelRect{0, 32 * b, 31, 32 * b + 31});
    const long long to_trace = 20000;
    DepthBackfill backfill(done, to_trace);
    std::vector<PixelRun> got[2];
    auto work = [&](int t) {
        for (long long p = t; p < to_trace; p += 2) {
            backfill.pixel_traced();
            for (PixelRun run = backfill.next_due(); !run.none(); run = backfill.next_due())
                got[t].push_back(run);
        }
    };
    std::thread a(work, 0), b(work, 1);
    a.join();
    b.join();
    std::vector<PixelRun> all(got[0]);
    all.insert(all.end(), got[1].begin(), got[1].end());
    EXPECT_EQ(all.size(), 50u * 32u);
    std::set<int> rows;
    for (const PixelRun& r : all)
        rows.insert(r.row);
    EXPECT_EQ(rows.size(), 50u * 32u);
}

} // namespace
} // namespace plenoptic
