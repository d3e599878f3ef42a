#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Runs a render and splits its run into stages by the lines it prints: wall time, CPU time and
peak memory per stage (BENCHMARKS.md, "The realistic raw, stage by stage").

    benchmarks/stage_profile.py [--json OUT] -- build/povray +I... +W7728 +H5368 ...

Every 0.2 s, and at every line the program prints, the program's CPU time (user + system of all
its threads, /proc/PID/stat) and its resident memory (/proc/PID/status VmRSS) are read; a stage
runs from the line that starts it to the line that starts the next. The stages are recognised by
the camera's own progress lines (a stage that prints nothing is folded into the one before it):

    trace        from the start (parsing included) to the first line after POV-Ray's render
    diffraction  "plenoptic camera: diffraction: convolving ..." (and POV-Ray writing the image)
    truth        "plenoptic camera: microimage centres: ..."
    raw          "plenoptic camera: raw ...: reading out ..."
    white image  "plenoptic camera: white image ...: W x H pixels" (each white image)
    metadata     what follows the last of these to the end of the run
"""

import argparse
import json
import os
import re
import subprocess
import sys
import threading
import time

STAGES = [
    ("diffraction", re.compile(r"plenoptic camera: diffraction: convolving")),
    ("truth", re.compile(r"plenoptic camera: microimage centres:")),
    ("raw", re.compile(r"plenoptic camera: raw .*: reading out")),
    ("white image", re.compile(r"plenoptic camera: white image .*: \d+ x \d+ pixels")),
]
TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid):
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS  # utime, stime (fields 14 and 15)


def rss_mib(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return 0.0


class Profile:
    def __init__(self, pid):
        self.pid, self.start = pid, time.monotonic()
        self.lock = threading.Lock()
        self.stages = [{"stage": "trace", "start_s": 0.0, "cpu_start_s": 0.0, "peak_rss_mib": 0.0}]
        self.last = (0.0, 0.0)

    def sample(self):
        try:
            t, cpu, rss = time.monotonic() - self.start, cpu_seconds(self.pid), rss_mib(self.pid)
        except (OSError, IndexError, ValueError):
            return  # the process has ended
        with self.lock:
            self.last = (t, cpu)
            stage = self.stages[-1]
            stage["peak_rss_mib"] = max(stage["peak_rss_mib"], rss)

    def line(self, text):
        self.sample()
        for name, pattern in STAGES:
            if pattern.search(text):
                with self.lock:
                    if self.stages[-1]["stage"] == name and name != "white image":
                        return
                    t, cpu = self.last
                    self.stages.append({"stage": name, "start_s": t, "cpu_start_s": cpu, "peak_rss_mib": 0.0})
                self.sample()
                return

    def finish(self, wall, cpu):
        rows = []
        for k, stage in enumerate(self.stages):
            end_t = self.stages[k + 1]["start_s"] if k + 1 < len(self.stages) else wall
            end_cpu = self.stages[k + 1]["cpu_start_s"] if k + 1 < len(self.stages) else cpu
            rows.append({"stage": stage["stage"], "wall_s": round(end_t - stage["start_s"], 2),
                         "cpu_s": round(end_cpu - stage["cpu_start_s"], 2), "peak_rss_mib": round(stage["peak_rss_mib"], 1)})
        return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="write the stages here as JSON")
    parser.add_argument("--log", help="write the program's output here")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("give the command after --")
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    profile = Profile(proc.pid)
    done = threading.Event()

    def poll():
        while not done.is_set():
            profile.sample()
            done.wait(0.2)

    poller = threading.Thread(target=poll, daemon=True)
    poller.start()
    log = open(args.log, "wb") if args.log else None
    pending = b""
    trace_time = trace_cpu = None
    after_trace_time = False  # the line after "Trace Time" gives its CPU seconds
    while True:
        chunk = proc.stdout.read1(65536)
        if not chunk:
            break
        if log:
            log.write(chunk)
        pending += chunk
        parts = re.split(rb"[\r\n]", pending)
        pending = parts.pop()
        for part in parts:
            text = part.decode("utf-8", errors="replace")
            m = re.search(r"Trace Time:.*\(([\d.]+) seconds\)", text)
            c = re.search(r"with ([\d.]+) CPU-seconds total", text) if after_trace_time else None
            if c:
                trace_cpu = float(c.group(1))
            after_trace_time = bool(m)
            if m:
                trace_time = float(m.group(1))
            profile.line(text)
    # The process's totals as the kernel counts them when it is reaped.
    _, wait_status, usage = os.wait4(proc.pid, 0)
    wall = time.monotonic() - profile.start
    done.set()
    status = os.waitstatus_to_exitcode(wait_status)
    proc.returncode = status
    cpu, hwm = usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0
    if log:
        log.close()
    rows = profile.finish(wall, cpu)
    result = {"command": command, "status": status, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
              "peak_rss_mib": round(hwm, 1), "povray_trace_time_s": trace_time, "povray_trace_cpu_s": trace_cpu, "stages": rows}
    print("%-12s %9s %9s %11s" % ("stage", "wall s", "CPU s", "peak MiB"))
    for r in rows:
        print("%-12s %9.1f %9.1f %11.1f" % (r["stage"], r["wall_s"], r["cpu_s"], r["peak_rss_mib"]))
    print("%-12s %9.1f %9.1f %11s   (POV-Ray's trace time %s s, %s CPU s; status %d)" % (
        "whole run", wall, cpu, "%.1f" % hwm if hwm else "?", trace_time, trace_cpu, status))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
            f.write("\n")
    return status


if __name__ == "__main__":
    sys.exit(main())
