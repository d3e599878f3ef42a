# SPDX-License-Identifier: AGPL-3.0-or-later
"""The command line of tools/bench (python3 -m plenoptic_bench is the same)."""
import argparse
import json
import os
import shutil
import sys
import tempfile
import time

from . import __doc__ as USAGE
from .build import section_build
from .dark import section_dark
from .spectral import section_spectral
from .arrays import section_arrays
from .refracting import section_refracting
from .dataset import section_dataset
from .fullsize import section_fullsize
from .lenses import section_lenses
from .overhead import section_overhead
from .real_lens import section_fullsize_real_lens, section_real_lens
from .realism import section_realism
from .report import plot, write_report
from .runner import Bench
from .threads import section_threads
from .trade import fixed_time_for_error, section_trade
from .util import ROOT, log, machine


def main():
    ap = argparse.ArgumentParser(description=USAGE, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--povray", default=os.path.join(ROOT, "build", "povray"))
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="tiny sizes, one run: check that it runs")
    ap.add_argument("--only", action="append", help="run only these sections")
    ap.add_argument("--out", default=os.path.join(ROOT, "benchmarks", "results"),
                    help="directory of results.json (quick.json with --quick) and the plots")
    ap.add_argument("--report", default=os.path.join(ROOT, "BENCHMARKS.md"),
                    help="the report written by a full run (default: the repository's BENCHMARKS.md)")
    ap.add_argument("--report-only", action="store_true", help="rewrite the report from the stored results.json")
    args = ap.parse_args()
    if args.report_only:
        # Rewrite the report (and plots) from the stored results, e.g. after editing analysis.md.
        stored_path = os.path.join(args.out, "results.json")
        with open(stored_path) as f:
            stored = json.load(f)
        write_report(stored, args.report, plot(stored, args.out), stored_path)
        log("wrote %s" % args.report)
        return 0
    if not os.path.exists(args.povray):
        print("bench: %s not found: run tools/build first" % args.povray, file=sys.stderr)
        return 2
    runs = 1 if args.quick else args.runs
    sections = args.only or ["overhead", "lenses", "trade", "dark", "threads", "fullsize", "real_lens",
                             "fullsize_real_lens", "realism", "spectral", "arrays", "refracting", "dataset"]
    os.makedirs(args.out, exist_ok=True)
    work = tempfile.mkdtemp(prefix="plenoptic-bench-")
    b = Bench(os.path.abspath(args.povray), work, runs)
    results = {"machine": machine(), "runs": runs, "quick": args.quick,
               "command": "tools/bench" + (" --quick" if args.quick else "")}
    name = "quick.json" if args.quick else "results.json"
    path = os.path.join(args.out, name)

    def save():
        old = {}
        if os.path.exists(path) and (args.only or not args.quick):
            with open(path) as f:
                old = json.load(f)
        old.update(results)
        with open(path, "w") as f:
            json.dump(old, f, indent=1)
        return old

    started = time.perf_counter()

    def done(section):
        nonlocal started
        log("%s: %.0f s" % (section, time.perf_counter() - started))
        started = time.perf_counter()

    # Instruction counts (callgrind) run in --quick mode too, at 32x32 (about 2 s a render under
    # valgrind), so that CI checks that they are still parsed; they are skipped with a log line
    # where valgrind is not installed.
    try:
        if "overhead" in sections:
            section_overhead(b, 64 if args.quick else 2048, runs if args.quick else max(runs, 9),
                             32 if args.quick else 256, results)
            save()
            done("overhead")
        if "lenses" in sections:
            section_lenses(b, 100 if args.quick else 1000, 32 if args.quick else 1000, results)
            save()
            done("lenses")
        if "trade" in sections:
            section_trade(b, (32, 24) if args.quick else (160, 120), [1, 4] if args.quick else [1, 4, 16, 64, 256, 1024],
                          16 if args.quick else 4096, results)
            for label, points in results["trade"]["configs"].items():
                for p in points:
                    if p["form"] == "adaptive":
                        tf = fixed_time_for_error(points, p["rmse"])
                        p["fixed_time_for_same_error_s"] = tf
                        p["time_ratio_to_fixed"] = (p["median_s"] / tf) if tf else None
            save()
            done("trade")
        if "dark" in sections:
            section_dark(b, 64 if args.quick else 1024, results)
            save()
            done("dark")
        if "threads" in sections:
            section_threads(b, 64 if args.quick else 512, results)
            save()
            done("threads")
        if "fullsize" in sections:
            if args.quick:
                section_fullsize(b, 193, 134, results)
            else:
                section_fullsize(b, 7728, 5368, results)
            done("fullsize")
        if "real_lens" in sections:
            section_real_lens(b, args.quick, 1 if args.quick else max(runs, 9), results)
            save()
            done("real_lens")
        if "fullsize_real_lens" in sections:
            if args.quick:
                section_fullsize_real_lens(b, 193, 134, results)
            else:
                section_fullsize_real_lens(b, 7728, 5368, results)
            save()
            done("fullsize_real_lens")
        if "realism" in sections:
            section_realism(b, (64, 48) if args.quick else (1440, 960), runs, 24 if args.quick else 96, results)
            save()
            done("realism")
        if "spectral" in sections:
            section_spectral(b, (64, 48) if args.quick else (480, 320), 1 if args.quick else max(runs, 5),
                             (48, 36) if args.quick else (240, 160), 256 if args.quick else 512,
                             (64, 48) if args.quick else (966, 671), 32 if args.quick else 128, results)
            save()
            done("spectral")
        if "arrays" in sections:
            section_arrays(b, (64, 48) if args.quick else (480, 320), 1 if args.quick else max(runs, 5),
                           (32, 24) if args.quick else (96, 64), results)
            save()
            done("arrays")
        if "refracting" in sections:
            section_refracting(b, (64, 48) if args.quick else (480, 320), (64, 48) if args.quick else (966, 671),
                               1 if args.quick else max(runs, 5), (32, 24) if args.quick else (96, 64), results)
            save()
            done("refracting")
        if "dataset" in sections:
            section_dataset(b, args.quick, runs, results)
            save()
            done("dataset")
        if "build" in sections:
            section_build(results)
            done("build")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    old = save()
    if not args.quick:
        plots = plot(old, args.out)
        write_report(old, args.report, plots, path)
        log("wrote %s" % args.report)
    log("wrote %s" % path)
    print("bench: 1 passed, 0 failed" if args.quick else "bench: done")
    return 0
