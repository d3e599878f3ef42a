#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-dataset as installed (P/bin/plenoptic-dataset): runs the package installed with it,
P/lib/python3/dist-packages/plenoptic_lf, found relative to this file's real path, so a moved
prefix keeps working. See docs/datasets.md and plenoptic-dataset(1)."""
import os
import sys

_bin = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(_bin), "lib", "python3", "dist-packages"))
from plenoptic_lf.dataset.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
