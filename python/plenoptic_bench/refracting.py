# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section refracting: refracting microlenses (plano-convex caps on a substrate, traced exactly)
against thin microlenses of the same paraxial focal length at equal samples, on the arrays
section's benchmark camera and on the Lytro-class raw of the fullsize section (a centre crop):
trace time, CPU time, the camera's instructions per pixel."""
import statistics

from .callgrind import have_callgrind
from .util import LOCATION, log

IOR = 1.5


def refracting_lens(focal_mm, cap_mm, substrate_mm):
    """Caps facing the scene of paraxial focal length focal_mm (R = f (n - 1)), and the distance
    to the sensor that puts the sensor where the thin lens's is: the rear principal plane lies
    L / n in front of the flat back (L = cap + substrate), so d = d_thin - L / n."""
    lens = ("lens { surface { radius %r } thickness %r ior %r substrate %r curved_side scene }"
            % (focal_mm * (IOR - 1), cap_mm, IOR, substrate_mm))
    return lens, (cap_mm + substrate_mm) / IOR


def cameras(main, pitch, focal, distance, pixel, samples, cap, substrate, extra=""):
    lens, shift = refracting_lens(focal, cap, substrate)
    thin = ("plenoptic %s %s microlens_array { hexagonal pitch %r focal_length %r distance %r } "
            "sensor { pixel_size %r %s } samples %d" % (LOCATION, main, pitch, focal, distance, pixel, extra, samples))
    refracting = ("plenoptic %s %s microlens_array { hexagonal pitch %r %s distance %r } "
                  "sensor { pixel_size %r %s } samples %d"
                  % (LOCATION, main, pitch, lens, distance - shift, pixel, extra, samples))
    return thin, refracting


# The arrays section's camera (16 mm f/4, pitch 0.1 mm, f = d = 0.4 mm, 10 um pixels, 16 samples):
# caps of R 0.2 mm, 0.01 mm tall, on a 0.05 mm substrate.
BENCH = dict(main="main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2.5 }", pitch=0.1, focal=0.4,
             distance=0.4, pixel=0.01, samples=16, cap=0.01, substrate=0.05)
# The fullsize section's Lytro-class raw (30 mm f/2, pitch 20 um, f = d = 40 um, 1.4 um pixels,
# 1 sample): caps of R 20 um, 4 um tall, on a 10 um substrate.
LYTRO = dict(main="main_lens { thin_lens focal_length 30 f_number 2 focus_distance 2.5 }", pitch=0.02, focal=0.04,
             distance=0.04, pixel=0.0014, samples=1, cap=0.004, substrate=0.01)


def section_refracting(b, size, lytro_size, runs, count_size, results):
    out = {"runs": runs, "cases": []}
    for name, case, (w, h) in (("benchmark camera", BENCH, size), ("Lytro-class raw, centre crop", LYTRO, lytro_size)):
        thin, refracting = cameras(**case)
        variants = {"thin": b.scene("refr_thin_" + str(len(out["cases"])), thin),
                    "refracting": b.scene("refr_refracting_" + str(len(out["cases"])), refracting)}
        log("refracting: %s, %dx%d, %d interleaved runs" % (name, w, h, runs))
        res = b.compare(variants, w, h, runs=runs)
        cpu = {k: statistics.median(v) for k, v in b.cpu_runs.items()}
        row = {"case": name, "size": [w, h], "samples": case["samples"],
               "thin_s": res["thin"][0], "refracting_s": res["refracting"][0],
               "thin_cpu_s": cpu["thin"], "refracting_cpu_s": cpu["refracting"],
               "thin_runs_s": res["thin"][2], "refracting_runs_s": res["refracting"][2],
               "thin_cpu_runs_s": b.cpu_runs["thin"], "refracting_cpu_runs_s": b.cpu_runs["refracting"]}
        if have_callgrind():
            cw, ch = count_size
            for label in ("thin", "refracting"):
                c = b.count(variants[label], cw, ch)
                row[label + "_ir_per_pixel"] = c["camera_ir_per_pixel"]
            row["count_size"] = [cw, ch]
        log("  thin %.2f s (CPU %.2f), refracting %.2f s (CPU %.2f)" % (row["thin_s"], row["thin_cpu_s"],
                                                                      row["refracting_s"], row["refracting_cpu_s"]))
        out["cases"].append(row)
    results["refracting"] = out


def refracting_report(L, results):
    r = results["refracting"]
    L.append("### Refracting against thin microlenses (`--only refracting`)\n")
    L.append("At equal samples, caps facing the scene (n 1.5) of the thin lenses' paraxial focal length, the sensor"
             " moved by L / n so that it sits where the thin lenses' is: the arrays section's benchmark camera (caps"
             " R 0.2 mm, 0.01 mm tall, 0.05 mm substrate) and the fullsize section's Lytro-class raw (caps R 20 um,"
             " 4 um tall, 10 um substrate) in a centre crop. Medians of %d interleaved runs; the camera's instructions"
             " per pixel under callgrind (one thread).\n" % r["runs"])
    L.append("| camera | size | samples | thin: trace, s | refracting: trace, s | ratio | thin: CPU, s | refracting: CPU, s"
             " | CPU ratio | camera instructions per pixel, thin | refracting | ratio |\n|---|---|---|---|---|---|---|---|---|---|---|---|")
    for c in r["cases"]:
        ir = ("%.0f | %.0f | %.2fx" % (c["thin_ir_per_pixel"], c["refracting_ir_per_pixel"],
                                       c["refracting_ir_per_pixel"] / c["thin_ir_per_pixel"])
              if "thin_ir_per_pixel" in c else "- | - | -")
        L.append("| %s | %dx%d | %d | %.2f | %.2f | %.2fx | %.2f | %.2f | %.2fx | %s |"
                 % (c["case"], c["size"][0], c["size"][1], c["samples"], c["thin_s"], c["refracting_s"],
                    c["refracting_s"] / c["thin_s"], c["thin_cpu_s"], c["refracting_cpu_s"],
                    c["refracting_cpu_s"] / c["thin_cpu_s"], ir))
    L.append("")
