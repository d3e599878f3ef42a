# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section build: a clean build and a rebuild after touching one camera source."""
import os
import shutil
import statistics
import subprocess
import tempfile
import time

from .util import ROOT, log


def section_build(results):
    log("build: clean build and rebuild after touching one camera source (ccache off)")
    tmp = tempfile.mkdtemp(prefix="bench-build-")
    env = dict(os.environ, CCACHE_DISABLE="1")
    existing = os.path.join(ROOT, "build", "_upstream", "povray-3.7.0.10")
    extra = ["-DPOVRAY_SOURCE_DIR=" + existing] if os.path.isdir(existing) else []
    subprocess.run(["cmake", "-S", ROOT, "-B", tmp, "-G", "Ninja"] + extra, env=env, check=True,
                   stdout=subprocess.DEVNULL)
    t0 = time.perf_counter()
    subprocess.run(["cmake", "--build", tmp, "-j%d" % os.cpu_count()], env=env, check=True, stdout=subprocess.DEVNULL)
    clean = time.perf_counter() - t0
    rebuilds = []
    for r in range(3):
        os.utime(os.path.join(ROOT, "source", "plenoptic", "camera/rays.cpp"))
        t0 = time.perf_counter()
        subprocess.run(["cmake", "--build", tmp, "-j%d" % os.cpu_count()], env=env, check=True, stdout=subprocess.DEVNULL)
        rebuilds.append(time.perf_counter() - t0)
    shutil.rmtree(tmp, ignore_errors=True)
    results["build"] = {"clean_s": clean, "rebuild_after_touch_s": statistics.median(rebuilds), "rebuild_runs_s": rebuilds}
