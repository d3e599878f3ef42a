# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section arrays: what manufacturing errors, lens tables, fill factors and masks cost at equal
samples (trace time, CPU, the camera's instructions per pixel), and whether finding a displaced
lens stays flat in the number of lenses (lens indices far from the axis, tables of 100 and of
200,000 rows)."""
import os
import statistics

from .callgrind import have_callgrind
from .util import LOCATION, log

PITCH = 0.1
ARRAY = "hexagonal pitch %r focal_length 0.4 distance 0.4" % PITCH
MAIN = "main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2.5 }"
ERRORS_POSITION = "errors { position 0.002 seed 1 }"
ERRORS_ALL = "errors { position 0.002, 0.001 focal_length 0.02 rotation 1 seed 1 }"


def camera(array_extra, sensor_extra="", samples=16):
    return ("plenoptic %s %s microlens_array { %s %s } sensor { pixel_size 0.01 %s } samples %d"
            % (LOCATION, MAIN, ARRAY, array_extra, sensor_extra, samples))


def bare(array_extra, sensor_extra=""):
    """No main lens: the picture is the same wherever the sensor sits over the array."""
    return ("plenoptic %s microlens_array { %s %s } sensor { pixel_size 0.01 %s } samples 16"
            % (LOCATION, ARRAY, array_extra, sensor_extra))


def write_table(path, rows_per_side):
    """A lens table of rows_per_side^2 lenses around (0, 0), every column filled."""
    with open(path, "w") as f:
        f.write("k,l,dx_mm,dy_mm,dz_mm,focal_length_mm,tilt_deg,tilt_azimuth_deg\n")
        half = rows_per_side // 2
        for l in range(-half, rows_per_side - half):
            for k in range(-half, rows_per_side - half):
                f.write("%d,%d,%.6g,%.6g,%.6g,%.6g,%.4g,%.4g\n" % (k, l, 0.001 * ((k * 7 + l * 3) % 5 - 2) / 2,
                                                                  0.001 * ((k * 3 + l * 5) % 5 - 2) / 2, 0.0,
                                                                  0.4 * (1 + 0.01 * ((k + l) % 3 - 1)),
                                                                  0.5 * ((k * l) % 3), (37 * k + 11 * l) % 360))
    return path


def section_arrays(b, size, runs, count_size, results):
    w, h = size
    small = write_table(os.path.join(b.work, "table_small.csv"), 10)       # 100 lenses
    large = write_table(os.path.join(b.work, "table_large.csv"), 448)      # 200,704 lenses
    variants = {"ideal array": b.scene("arrays_ideal", camera("")),
                "errors: position": b.scene("arrays_position", camera(ERRORS_POSITION)),
                "errors: position, focal length, rotation": b.scene("arrays_all", camera(ERRORS_ALL)),
                "lens_table, 200,704 lenses": b.scene("arrays_table", camera('lens_table "%s"' % large)),
                "fill_factor 0.9, mask on": b.scene("arrays_masked", camera("fill_factor 0.9 mask on")),
                "fill_factor 0.9, clear gap": b.scene("arrays_clear", camera("fill_factor 0.9"))}
    log("arrays: cost at equal samples, %dx%d, %d interleaved runs" % (w, h, runs))
    res = b.compare(variants, w, h, runs=runs)
    cpu = {k: statistics.median(v) for k, v in b.cpu_runs.items()}
    base = "ideal array"
    rows = [{"variant": k, "median_trace_s": t, "ratio": t / res[base][0], "cpu_s": cpu[k],
             "cpu_ratio": cpu[k] / cpu[base], "peak_rss_mib": m, "runs_s": ts} for k, (t, m, ts) in res.items()]
    for r in rows:
        log("  %s: %.2f s (%.3fx), CPU %.2f s" % (r["variant"], r["median_trace_s"], r["ratio"], r["cpu_s"]))
    out = {"size": [w, h], "runs": runs, "rows": rows}
    if have_callgrind():
        cw, ch = count_size
        counts = []
        # A bare array (no main lens: the same picture wherever the sensor sits over it) with its
        # lenses near (0, 0), 10^3 and 10^5 lenses away (a sensor offset of whole pitches: the lens
        # lookup must not care), and the benchmark camera with tables of 100 and 200,704 rows.
        offsets = [("bare array, ideal", bare("")),
                   ("bare array, errors, lenses near (0, 0)", bare(ERRORS_ALL)),
                   ("bare array, errors, lenses near k = 1000", bare(ERRORS_ALL, "offset <%r, 0>" % (1000 * PITCH))),
                   ("bare array, errors, lenses near k = 100000", bare(ERRORS_ALL, "offset <%r, 0>" % (100000 * PITCH))),
                   ("errors: position, focal length, rotation", camera(ERRORS_ALL)),
                   ("lens_table, 100 lenses", camera('lens_table "%s"' % small)),
                   ("lens_table, 200,704 lenses", camera('lens_table "%s"' % large))]
        for label, cam in [("ideal array", camera(""))] + offsets:
            c = b.count(b.scene("count_" + str(len(counts)), cam), cw, ch)
            counts.append({"variant": label, "camera_ir_per_pixel": c["camera_ir_per_pixel"], "total_ir": c["total_ir"]})
            log("  %s: camera %.0f instructions per pixel" % (label, c["camera_ir_per_pixel"]))
        out["callgrind"] = {"size": [cw, ch], "rows": counts}
    results["arrays"] = out


def arrays_report(L, results):
    r = results["arrays"]
    L.append("## Real microlens arrays (`--only arrays`)\n")
    L.append("Manufacturing errors, lens tables, fill factors and masks (docs/camera.md, \"Real microlens arrays\") on"
             " the benchmark scene: a 16 mm f/4 thin lens, plenoptic 1.0 hexagonal array (pitch 0.1 mm, f = d ="
             " 0.4 mm), 10 um pixels, 16 samples, %dx%d, %d interleaved runs, POV-Ray's trace time and the"
             " process's CPU time. Errors: position 0.002 mm (0.001 along z), focal length 2 %%, rotation 1 degree.\n"
             % (r["size"][0], r["size"][1], r["runs"]))
    L.append("| variant | trace, s (median) | ratio | CPU, s | CPU ratio | peak RSS, MiB |\n|---|---|---|---|---|---|")
    for row in r["rows"]:
        L.append("| %s | %.2f | %.3fx | %.2f | %.3fx | %.0f |" % (row["variant"], row["median_trace_s"], row["ratio"],
                                                               row["cpu_s"], row["cpu_ratio"], row["peak_rss_mib"]))
    cg = r.get("callgrind")
    if cg:
        base = cg["rows"][0]["camera_ir_per_pixel"]
        L.append("\nThe camera's instructions per pixel (callgrind, one thread, %dx%d; the per-pixel work minus the"
                 " scene's rays):\n" % (cg["size"][0], cg["size"][1]))
        L.append("| variant | camera instructions per pixel | ratio to the ideal array |\n|---|---|---|")
        for row in cg["rows"]:
            L.append("| %s | %.0f | %.3fx |" % (row["variant"], row["camera_ir_per_pixel"], row["camera_ir_per_pixel"] / base))
    L.append("")
