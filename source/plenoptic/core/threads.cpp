// SPDX-License-Identifier: AGPL-3.0-or-later
// Work spread over threads (see the header).

#include "plenoptic/core/threads.h"

#include <algorithm>
#include <thread>
#include <vector>

namespace plenoptic {

int thread_count(int requested, std::size_t items)
{
    const int wanted = requested > 0 ? requested : int(std::max(1u, std::thread::hardware_concurrency()));
    return int(std::max<std::size_t>(1, std::min<std::size_t>(std::size_t(wanted), items)));
}

void run_on_threads(int count, const std::function<void(int)>& work)
{
    std::vector<std::thread> workers;
    for (int t = 1; t < count; ++t)
        workers.emplace_back(work, t);
    work(0);
    for (std::thread& worker : workers)
        worker.join();
}

} // namespace plenoptic
