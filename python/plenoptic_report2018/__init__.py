# SPDX-License-Identifier: AGPL-3.0-or-later
"""The figures of docs/report2018.md: every scene of scenes/report2018 rendered, shown at one
exposure, with a zoomed crop of the raw's centre (figures.py; tools/report2018-figures)."""
