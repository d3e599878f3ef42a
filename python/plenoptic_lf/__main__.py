# SPDX-License-Identifier: AGPL-3.0-or-later
"""python3 -m plenoptic_lf: the plenoptic-decode command."""

import sys

from .cli import main

sys.exit(main())
