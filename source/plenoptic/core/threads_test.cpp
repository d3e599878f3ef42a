// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the thread helper: each thread index runs once, index 0 on the calling thread, and the
// thread count follows the request and the work items.

#include <algorithm>
#include <atomic>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/core/threads.h"

namespace plenoptic {
namespace {

TEST(Threads, EachIndexRunsOnceAndZeroOnTheCaller)
{
    for (int count : {0, 1, 2, 5}) {
        std::mutex guard;
        std::multiset<int> seen;
        std::set<std::thread::id> ids;
        std::thread::id zero;
        run_on_threads(count, [&](int t) {
            std::lock_guard<std::mutex> lock(guard);
            seen.insert(t);
            ids.insert(std::this_thread::get_id());
            if (t == 0)
                zero = std::this_thread::get_id();
        });
        const int expected = count < 1 ? 1 : count;
        EXPECT_EQ(int(seen.size()), expected) << count;
        for (int t = 0; t < expected; ++t)
            EXPECT_EQ(seen.count(t), 1u) << count << " " << t;
        EXPECT_EQ(int(ids.size()), expected) << count;  // each on a thread of its own
        EXPECT_EQ(zero, std::this_thread::get_id()) << count;
    }
}

TEST(Threads, SharedCounterHandsOutEveryItemOnce)
{
    const int items = 1000;
    std::vector<std::atomic<int>> hits(items);
    for (std::atomic<int>& h : hits)
        h = 0;
    std::atomic<int> next(0);
    run_on_threads(thread_count(4, items), [&](int) {
        for (int i = next++; i < items; i = next++)
            ++hits[std::size_t(i)];
    });
    for (int i = 0; i < items; ++i)
        EXPECT_EQ(hits[std::size_t(i)].load(), 1) << i;
}

TEST(Threads, CountFollowsRequestAndItems)
{
    EXPECT_EQ(thread_count(3, 10), 3);
    EXPECT_EQ(thread_count(3, 2), 2);
    EXPECT_EQ(thread_count(3, 0), 1);
    const int machine = int(std::max(1u, std::thread::hardware_concurrency()));
    EXPECT_EQ(thread_count(0, 1000000), machine);
    EXPECT_EQ(thread_count(-1, 1000000), machine);
    EXPECT_EQ(thread_count(0), machine);
    EXPECT_EQ(thread_count(7), 7);
}

} // namespace
} // namespace plenoptic
