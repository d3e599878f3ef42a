# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section fullsize: a Lytro Illum-class raw at full size."""
import statistics

from .util import LOCATION, log


def section_fullsize(b, w, h, results):
    log("full size: Lytro Illum-class raw %dx%d" % (w, h))
    scene = b.scene("fullsize", "plenoptic %s main_lens { thin_lens focal_length 30 f_number 2 focus_distance 2.5 } "
                    "microlens_array { hexagonal pitch 0.02 focal_length 0.04 distance 0.04 } "
                    "sensor { pixel_size 0.0014 } samples 1" % LOCATION)
    runs = []
    for r in range(max(1, min(b.runs, 3))):
        s, m, _ = b.render(scene, w, h)
        runs.append((s, m))
    results["fullsize"] = {"size": [w, h], "median_s": statistics.median(r[0] for r in runs),
                           "peak_rss_mib": max(r[1] for r in runs), "runs": len(runs),
                           "runs_s": [r[0] for r in runs]}
