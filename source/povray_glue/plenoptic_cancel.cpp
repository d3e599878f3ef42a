// SPDX-License-Identifier: AGPL-3.0-or-later
// The session's cancel request, as POV-Ray's own front end keeps it (see plenoptic_cancel.h).

#include "povray_glue/plenoptic_cancel.h"

#include "vfe.h"

namespace plenoptic {

bool render_cancel_requested()
{
    try {
        vfe::vfeSession* session = vfe::vfeSession::GetSessionFromThreadID();
        return session != nullptr && session->GetCancelRequested();
    } catch (...) {
        return false;  // no session (the backend is gone): nothing to ask
    }
}

} // namespace plenoptic
