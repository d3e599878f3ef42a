# SPDX-License-Identifier: AGPL-3.0-or-later
"""python3 -m plenoptic_lf.dataset: the plenoptic-dataset command (what Slurm's job script runs)."""
import sys

from .cli import main

sys.exit(main())
