# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section overhead: the perspective camera against the plenoptic camera's cheapest forms."""
import math
import statistics

from .callgrind import have_callgrind
from .runner import thin_main
from .util import LOCATION, log


def perspective_camera(w, h, px, distance):
    angle = 2 * math.degrees(math.atan(w * px / (2 * distance)))
    return "perspective %s right x*%d/%d up y angle %.12g" % (LOCATION, w, h, angle)


def overhead_cameras(size):
    D = 16.0 * 2500 / (2500 - 16)  # thin lens f=16 focused at 2.5 m
    px = 0.01
    return {
        "perspective": perspective_camera(size, size, px, D),
        "plenoptic, pinhole main lens, no array":
            "plenoptic %s main_lens { pinhole distance %.12g } sensor { pixel_size %g } samples 1" % (LOCATION, D, px),
        "plenoptic, thin main lens + pinhole microlenses":
            "plenoptic %s %s microlens_array { hexagonal pitch 0.16 pinhole distance 0.64 } sensor { pixel_size %g } samples 1"
            % (LOCATION, thin_main(), px),
    }


def section_overhead(b, size, runs, count_size, results):
    log("overhead: perspective vs plenoptic at %dx%d, %d interleaved runs" % (size, size, runs))
    cameras = overhead_cameras(size)
    names = {"perspective": "ovh_persp", "plenoptic, pinhole main lens, no array": "ovh_pinhole",
             "plenoptic, thin main lens + pinhole microlenses": "ovh_array"}
    variants = {label: b.scene(names[label], cam) for label, cam in cameras.items()}
    others = [k for k in variants if k != "perspective"]

    # Perspective in the middle of every round, so that each variant's run r is rendered right
    # before or right after perspective's run r; the two others swap sides every round.
    def order(r):
        o = others if r % 2 == 0 else others[::-1]
        return [o[0], "perspective"] + o[1:]

    res = b.compare(variants, size, size, runs=runs, order=order)
    cpu = b.cpu_runs
    # CPU time of start-up and parsing alone (a 16x16 render of the same scene), subtracted so that
    # the CPU ratio compares the rendering, as the trace-time ratio does.
    b.compare(variants, 16, 16, runs=min(runs, 5))
    startup_cpu = {label: statistics.median(v) for label, v in b.cpu_runs.items()}
    render_cpu = {label: statistics.median(v) - startup_cpu[label] for label, v in cpu.items()}
    base_t, base_m, base_ts = res["perspective"]
    rows = []
    for label, (t, m, ts) in res.items():
        paired = [x / y for x, y in zip(ts, base_ts)]
        rows.append({"camera": label, "median_s": t, "ratio": t / base_t,
                     "median_paired_ratio": statistics.median(paired), "paired_ratios": paired,
                     "cpu_render_s": render_cpu[label], "cpu_ratio": render_cpu[label] / render_cpu["perspective"],
                     "cpu_runs_s": cpu[label], "cpu_startup_s": startup_cpu[label],
                     "peak_rss_mib": m, "rss_minus_perspective_mib": m - base_m, "runs_s": ts})
    results["overhead"] = {"size": size, "runs": runs, "rows": rows}
    if count_size and have_callgrind():
        log("overhead: instruction counts (callgrind) at %dx%d" % (count_size, count_size))
        counts = {label: b.count(b.scene(names[label] + "_cg", cam), count_size, count_size)
                  for label, cam in overhead_cameras(count_size).items()}
        base = counts["perspective"]
        crows = []
        for label, c in counts.items():
            crows.append(dict(c, camera=label, total_ratio=c["total_ir"] / base["total_ir"],
                              pixel_work_ratio=c["pixel_work_ir"] / base["pixel_work_ir"]))
            log("  %s: camera %.0f instructions per pixel, per-pixel work %.4fx perspective"
                % (label, c["camera_ir_per_pixel"], crows[-1]["pixel_work_ratio"]))
        results["overhead_callgrind"] = {"size": count_size, "rows": crows}
    elif count_size:
        log("overhead: valgrind not installed, no instruction counts")
        results["overhead_callgrind"] = None
