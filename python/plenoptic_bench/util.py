# SPDX-License-Identifier: AGPL-3.0-or-later
"""Repository paths, logging and the machine's description, shared by every section."""
import os
import platform
import sys

# This package lives in <repository>/python/plenoptic_bench; the benchmark uses the repository's
# benchmark scene and builds, so it runs from the source tree only.
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCENE_INC = os.path.join(ROOT, "benchmarks", "scene.inc")

LOCATION = "location <0, 0.6, -2.5> look_at <0, 0.4, 0>"


def log(msg):
    print("bench: " + msg, file=sys.stderr, flush=True)


def machine():
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    return "%s, %d cores, %.0f GiB, %s" % (cpu, os.cpu_count(), mem, platform.platform())
