# SPDX-License-Identifier: AGPL-3.0-or-later
"""python3 -m plenoptic_bench: the same as tools/bench."""
import sys

from .cli import main

sys.exit(main())
