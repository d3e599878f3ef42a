# SPDX-License-Identifier: AGPL-3.0-or-later
"""Bench: one render with POV-Ray's trace time, its CPU time and peak memory; interleaved
comparisons; the scene worlds and cameras the sections share."""
import os
import re
import statistics
import sys

from plenoptic_lf.povray import povray_command, run_povray

from .callgrind import callgrind_counts
from .util import SCENE_INC


# Linux hands a child the peak resident set of the process it was forked from (the copy counts
# until exec), so once this script has loaded numpy and OpenImageIO (about 170 MiB) a povray it
# started itself would "peak" at least that high. povray is started instead by this small Python
# (-S: about 8 MiB), which forks it, waits, and writes its peak (KiB) to argv[1].
SPAWN = """
import os, sys
pid = os.fork()
if pid == 0:
    try:
        os.execv(sys.argv[2], sys.argv[2:])
    finally:
        os._exit(127)
_, status, usage = os.wait4(pid, 0)
with open(sys.argv[1], "w") as f:
    f.write("%d %.6f" % (usage.ru_maxrss, usage.ru_utime + usage.ru_stime))
code = os.waitstatus_to_exitcode(status)
sys.exit(code if code >= 0 else 128 - code)
"""


class Bench:
    def __init__(self, povray, work, runs):
        self.povray = povray
        self.work = work
        self.runs = runs
        self.use_trace_time = True

    def scene(self, name, camera, world=None):
        path = os.path.join(self.work, name + ".pov")
        with open(path, "w") as f:
            f.write((world or '#include "%s"' % SCENE_INC) + "\ncamera { %s }\n" % camera)
        return path

    def render(self, scene, w, h, out=None, extra=()):
        """One render; returns (seconds, peak RSS in MiB, output path)."""
        out = out or os.path.splitext(scene)[0] + ".png"
        cmd = povray_command(self.povray, scene, out, w, h, ["-D", "-P", "+FN16"] + list(extra))
        # POV-Ray's messages go to a file: a pipe read only at the end would fill and stall it.
        log_path = os.path.join(self.work, "povray.log")
        rss_path = os.path.join(self.work, "povray.maxrss")
        open(log_path, "wb").close()
        run = run_povray([sys.executable, "-S", "-E", "-c", SPAWN, rss_path] + cmd, cwd=self.work, log=log_path)
        status, seconds, err = run.returncode, run.seconds, run.output
        # The whole process on the clock: start-up, parsing, trace and what the camera writes after
        # it (metadata, depth map, microimage centres).
        self.last_wall_s = seconds
        if status != 0:
            raise RuntimeError("povray failed on %s:\n%s" % (scene, err[-1500:]))
        with open(rss_path) as f:
            maxrss_text, cpu_text = f.read().split()
        maxrss_kib = int(maxrss_text)
        # CPU time (user + system) of the whole process: unlike the clock, it leaves out the time
        # the virtual machine's host gives the core to others (steal), the main noise here.
        self.last_cpu_s = float(cpu_text)
        # POV-Ray's own "Trace Time" excludes its fixed start-up cost (about 0.5 s here),
        # which would otherwise flatten every ratio.
        m = re.search(r"Trace Time:.*\(\s*([0-9.]+) seconds\)", err)
        if m and self.use_trace_time:
            seconds = float(m.group(1))
        return seconds, maxrss_kib / 1024.0, out

    def compare(self, variants, w, h, extra=(), runs=None, order=None):
        """variants: {label: scene}; interleaved runs; returns {label: (median s, max RSS MiB, times)}.
        order(r), if given, lists the labels in the order of run r (default: as in variants)."""
        times = {k: [] for k in variants}
        rss = {k: 0.0 for k in variants}
        self.cpu_runs = {k: [] for k in variants}  # CPU seconds of each run, same order as the times
        self.wall_runs = {k: [] for k in variants}  # the whole process's clock time, likewise
        for r in range(runs or self.runs):
            for label in (order(r) if order else variants):
                scene = variants[label]
                s, m, _ = self.render(scene, w, h, extra=extra)
                times[label].append(s)
                self.cpu_runs[label].append(self.last_cpu_s)
                self.wall_runs[label].append(self.last_wall_s)
                rss[label] = max(rss[label], m)
        return {k: (statistics.median(v), rss[k], v) for k, v in times.items()}

    def white(self, name, camera, w, h):
        """The camera's render of a world that is white in every direction, as linear RGB: each
        sample that passes the apertures returns exactly 1, a blocked one 0."""
        scene = self.scene(name, camera, WHITE_WORLD)
        _, _, png = self.render(scene, w, h, extra=["+WT2", "File_Gamma=1.0"])
        return read_linear(png)

    def count(self, scene, w, h):
        """Instruction counts of one single-threaded render under callgrind (see callgrind_counts)."""
        out = os.path.join(self.work, "callgrind.out")
        png = os.path.join(self.work, "callgrind.png")
        cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out, self.povray, "+I" + scene,
               "+O" + png, "+W%d" % w, "+H%d" % h, "-D", "-P", "+FN16", "+WT1"]
        log_path = os.path.join(self.work, "valgrind.log")
        open(log_path, "wb").close()
        run = run_povray(cmd, cwd=self.work, log=log_path)
        if run.returncode != 0:
            err = run.output
            raise RuntimeError("povray under callgrind failed on %s:\n%s" % (scene, err[-1500:]))
        counts = callgrind_counts(out, w * h)
        os.remove(out)
        return counts


def thin_main(f=16, n=4, focus=2.5):
    return "main_lens { thin_lens focal_length %g f_number %g focus_distance %g }" % (f, n, focus)


# A scene whose every ray costs the same and almost nothing: what remains is the camera's cost.
EMPTY_WORLD = "#version 3.7;\nglobal_settings { assumed_gamma 1 }\nbackground { rgb <0.5, 0.6, 0.7> }"


# Every direction white: a sample that passes the apertures returns exactly 1, a blocked one 0.
WHITE_WORLD = "#version 3.7;\nglobal_settings { assumed_gamma 1 }\nsky_sphere { pigment { rgb 1 } }"


def read_linear(path):
    """A linear render's RGB values (H, W, 3) float32, through the decoder package's one image
    reader (OpenImageIO's ImageInput: a file rewritten within the same second is read anew)."""
    from plenoptic_lf.images import ImageReadError, read_image
    try:
        return read_image(path)[..., :3]
    except ImageReadError as e:
        raise RuntimeError(str(e)) from None
