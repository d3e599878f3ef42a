# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section realism: the cost of irradiance radiometry, diffraction and the sensor's
read-out, each against the plain render of the same camera, on the whole process's clock and CPU
time (diffraction and the read-out run after the trace, so POV-Ray's trace time misses them)."""
import statistics

from .callgrind import have_callgrind
from .util import LOCATION, log

# Lytro-class optics: a 6.45 mm f/2 lens, 14 um f/2 hexagonal microlenses at d = f, 1.4 um pixels:
# the green Airy radius of the microlenses is 1.34 um, about one pixel.
LYTRO = ("main_lens { thin_lens focal_length 6.45 f_number 2 focus_distance 2.5 } "
         "microlens_array { hexagonal pitch 0.014 focal_length 0.028 distance 0.028 } ")
SENSOR = "pixel_size 0.0014"
CHAIN = "bayer rggb bit_depth 12 full_well 10000 read_noise 3 prnu 0.01 dsnu 1 seed 1"


def realism_cameras():
    base = "plenoptic %s %s sensor { %s%s } samples 16 %s"
    return {
        "plain (flat radiometry)": base % (LOCATION, LYTRO, SENSOR, "", ""),
        "radiometry irradiance": base % (LOCATION, LYTRO, SENSOR, "", "radiometry irradiance"),
        "diffraction (Airy radius 0.96 px in green)": base % (LOCATION, LYTRO, SENSOR, "", "diffraction"),
        # Four times the wavelengths: the same picture, an Airy radius of 3.8 pixels.
        "diffraction at 4x the wavelengths (Airy radius 3.8 px)":
            base % (LOCATION, LYTRO, SENSOR, "", "diffraction wavelengths <2440, 2200, 1860>"),
        "sensor read-out (Bayer, 12 bits)": base % (LOCATION, LYTRO, SENSOR, " " + CHAIN, ""),
        "all three": base % (LOCATION, LYTRO, SENSOR, " " + CHAIN, "radiometry irradiance diffraction"),
    }


def section_realism(b, size, runs, count_size, results):
    w, h = size
    log("realism: radiometry, diffraction and read-out at %dx%d, 16 samples, %d interleaved runs" % (w, h, runs))
    cameras = realism_cameras()
    variants = {label: b.scene("realism_%d" % i, cam) for i, (label, cam) in enumerate(cameras.items())}
    b.use_trace_time = False  # the whole process's clock: diffraction and the read-out follow the trace
    try:
        res = b.compare(variants, w, h, runs=runs)
    finally:
        b.use_trace_time = True
    cpu = {k: statistics.median(v) for k, v in b.cpu_runs.items()}
    base_label = "plain (flat radiometry)"
    base_t = res[base_label][0]
    rows = []
    for label, (t, m, ts) in res.items():
        paired = [x / y for x, y in zip(ts, res[base_label][2])]
        rows.append({"variant": label, "median_wall_s": t, "ratio": t / base_t,
                     "median_paired_ratio": statistics.median(paired), "cpu_s": cpu[label],
                     "cpu_ratio": cpu[label] / cpu[base_label], "peak_rss_mib": m, "runs_s": ts})
        log("  %s: %.2f s (%.3fx), CPU %.2f s (%.3fx)" % (label, t, t / base_t, cpu[label], cpu[label] / cpu[base_label]))
    results["realism"] = {"size": [w, h], "runs": runs, "samples": 16, "rows": rows}
    if count_size and have_callgrind():
        log("realism: instruction counts (callgrind) at %dx%d" % (count_size, count_size))
        counts = {label: b.count(b.scene("realism_cg_%d" % i, cam), count_size, count_size)
                  for i, (label, cam) in enumerate(cameras.items())}
        base = counts[base_label]
        results["realism_callgrind"] = {"size": count_size, "rows": [
            {"variant": label, "total_ir": c["total_ir"], "total_ratio": c["total_ir"] / base["total_ir"]}
            for label, c in counts.items()]}
    elif count_size:
        results["realism_callgrind"] = None
