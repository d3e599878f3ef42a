# SPDX-License-Identifier: AGPL-3.0-or-later
import sys

from plenoptic_report2018.figures import main

sys.exit(main())
