// SPDX-License-Identifier: AGPL-3.0-or-later
// Progress of the long steps of a camera's setup (make_camera), for whoever runs it: the tables a
// traced main lens needs (pupil bounds, lit area) cost a fixed number of traces, each linear in
// the lens's surfaces, so a lens of thousands of surfaces sets up for tens of seconds. Those
// steps report here now and then; the caller installs a reporter for the thread that sets up
// (the POV-Ray glue prints a progress line and lets Ctrl-C stop the parse by throwing from it).
// Without one, reporting does nothing. Header only; no POV-Ray dependency.

#ifndef PLENOPTIC_SETUP_PROGRESS_H
#define PLENOPTIC_SETUP_PROGRESS_H

#include <functional>
#include <utility>

namespace plenoptic {

// step: what is being computed ("pupil bounds", "lit-area table"); done of total parts. May throw
// to abandon the setup (the steps hold their state in standard containers only).
using SetupReporter = std::function<void(const char* step, int done, int total)>;

inline SetupReporter& current_setup_reporter()
{
    static thread_local SetupReporter reporter;
    return reporter;
}

inline void report_setup(const char* step, int done, int total)
{
    const SetupReporter& reporter = current_setup_reporter();
    if (reporter)
        reporter(step, done, total);
}

// Installs a reporter on this thread for its lifetime.
class ScopedSetupReporter {
public:
    explicit ScopedSetupReporter(SetupReporter reporter) : previous_(current_setup_reporter())
    {
        current_setup_reporter() = std::move(reporter);
    }
    ~ScopedSetupReporter() { current_setup_reporter() = previous_; }
    ScopedSetupReporter(const ScopedSetupReporter&) = delete;
    ScopedSetupReporter& operator=(const ScopedSetupReporter&) = delete;

private:
    SetupReporter previous_;
};

} // namespace plenoptic

#endif
