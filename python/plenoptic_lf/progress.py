# SPDX-License-Identifier: AGPL-3.0-or-later
"""Progress messages on stderr."""

from __future__ import annotations

import sys
import time


class Progress:
    """Stage messages and, for stages longer than a second, percentages on stderr."""

    def __init__(self, enabled: bool = True, prefix: str = "plenoptic-decode") -> None:
        self.enabled = enabled
        self.prefix = prefix
        self._label: str | None = None
        self._stage_start = 0.0
        self._last_report = 0.0

    def stage(self, label: str) -> None:
        self._label = label
        self._stage_start = self._last_report = time.monotonic()
        if self.enabled:
            print("%s: %s" % (self.prefix, label), file=sys.stderr, flush=True)

    def update(self, done: float, total: float) -> None:
        if not self.enabled or total <= 0:
            return
        now = time.monotonic()
        if now - self._stage_start > 1.0 and (now - self._last_report > 1.0 or done == total):
            self._last_report = now
            print("%s:   %s %d%%" % (self.prefix, self._label, int(100 * done / total)), file=sys.stderr, flush=True)
