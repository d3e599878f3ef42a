# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section threads: one render thread against two."""
import statistics

from .runner import thin_main
from .util import LOCATION, log


def section_threads(b, size, results):
    log("threads: 1 vs 2 at %dx%d" % (size, size))
    scene = b.scene("threads", "plenoptic %s %s microlens_array { hexagonal pitch 0.16 focal_length 0.64 distance 0.64 } "
                    "sensor { pixel_size 0.01 } samples 4" % (LOCATION, thin_main()))
    t = {1: [], 2: []}
    for r in range(b.runs):
        for n in (1, 2):
            s, _, _ = b.render(scene, size, size, extra=["+WT%d" % n])
            t[n].append(s)
    m1, m2 = statistics.median(t[1]), statistics.median(t[2])
    results["threads"] = {"size": size, "one_thread_s": m1, "two_threads_s": m2, "speedup": m1 / m2,
                          "runs_s": {"1": t[1], "2": t[2]}}
