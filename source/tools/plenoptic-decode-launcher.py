#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode as installed (P/bin/plenoptic-decode): runs the decoder package installed
with it, P/lib/python3/dist-packages/plenoptic_lf, found relative to this file's real path, so
a moved prefix keeps working. See docs/install.md and plenoptic-decode(1)."""
import os
import sys

_bin = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(_bin), "lib", "python3", "dist-packages"))
from plenoptic_lf.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
