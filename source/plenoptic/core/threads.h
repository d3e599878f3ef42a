// SPDX-License-Identifier: AGPL-3.0-or-later
// Work spread over threads, the calling thread among them: the one shape every parallel loop of
// the camera's set-up and outputs takes (the white image, diffraction, the read-out, the
// microimage truth). Each loop hands out its own work items (an atomic counter) and writes each
// result into its own slot, so its output does not depend on the thread count.

#ifndef PLENOPTIC_THREADS_H
#define PLENOPTIC_THREADS_H

#include <cstddef>
#include <functional>

namespace plenoptic {

// How many threads a request for `requested` means: `requested` when positive, else the machine's
// hardware threads (at least 1); never more than `items` (at least 1), the work items to share
// (no limit when not given).
int thread_count(int requested, std::size_t items = std::size_t(-1));

// Runs work(t) for t = 0 .. count - 1 at once, t = 0 on the calling thread (the one that may poll
// for cancellation and report progress), the others on threads of their own; returns when all have
// returned. count < 1 runs work(0) alone.
void run_on_threads(int count, const std::function<void(int)>& work);

} // namespace plenoptic

#endif
