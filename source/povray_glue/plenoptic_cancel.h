// SPDX-License-Identifier: AGPL-3.0-or-later
// Whether the user asked POV-Ray to stop (Ctrl-C, SIGTERM...): long work of ours that runs
// outside the render (the microimage ground truth, written after the image) polls it so that it
// stops promptly.

#ifndef POVRAY_GLUE_PLENOPTIC_CANCEL_H
#define POVRAY_GLUE_PLENOPTIC_CANCEL_H

namespace plenoptic {

// True once the console front end has asked the session to cancel (it does so on SIGINT, SIGTERM,
// SIGQUIT and SIGPIPE); false when there is no session.
bool render_cancel_requested();

} // namespace plenoptic

#endif
