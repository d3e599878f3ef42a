# SPDX-License-Identifier: AGPL-3.0-or-later
"""BENCHMARKS.md from results.json, and the plots."""
import os

from .dataset_report import dataset_report
from .util import ROOT, log


def fmt(x, digits=3):
    return "-" if x is None else ("%.*g" % (digits, x))


def fixed(x, digits=3):
    return "-" if x is None else ("%.*f" % (digits, x))


def pct(x, digits=1):
    return "-" if x is None else ("%.*f %%" % (digits, 100 * x))


def mega(x):
    return "-" if x is None else ("%.1f" % (x / 1e6))


def report_path(target, report):
    """How the report names a file: relative to the report's folder (a link that works there)."""
    return os.path.relpath(target, os.path.dirname(os.path.abspath(report)))


def lens_table(L, o):
    L.append("| lenses | pixels lit | trace time, s | ratio to 100 lenses | time per lit pixel, us"
             " | ratio to 100 lenses (per lit pixel) | peak RSS, MiB |\n|---|---|---|---|---|---|---|")
    for r in o["rows"]:
        L.append("| %d | %s | %.3f | %s | %s | %s | %.1f |" % (
            r["lenses"], pct(r.get("lit_pixel_fraction")), r["median_s"], fixed(r["ratio_to_100"]),
            fixed(r.get("us_per_lit_pixel")), fixed(r.get("per_lit_pixel_ratio_to_100")), r["peak_rss_mib"]))
    L.append("")


def realism_report(L, results):
    """Section realism: radiometry, diffraction and the read-out against the plain render."""
    r = results["realism"]
    L.append("## Radiometry, diffraction and the sensor's read-out (`--only realism`)\n")
    L.append("The realism options' costs, each against the plain render of the same camera: the benchmark scene through"
             " Lytro-class optics (6.45 mm f/2 thin lens, hexagonal 14 um f/2 microlenses at d = f, 1.4 um pixels),"
             " %dx%d, %d samples, %d interleaved runs each. Diffraction and the read-out run after the trace, so"
             " the times are the whole process's (clock and CPU), not POV-Ray's trace time.\n"
             % (r["size"][0], r["size"][1], r["samples"], r["runs"]))
    L.append("| variant | whole process, s (median) | ratio | paired ratio (median) | CPU, s | CPU ratio | peak RSS, MiB |")
    L.append("|---|---|---|---|---|---|---|")
    for row in r["rows"]:
        L.append("| %s | %.2f | %.3fx | %.3fx | %.2f | %.3fx | %.0f |" % (
            row["variant"], row["median_wall_s"], row["ratio"], row["median_paired_ratio"], row["cpu_s"],
            row["cpu_ratio"], row["peak_rss_mib"]))
    cg = results.get("realism_callgrind")
    if cg:
        L.append("\nInstructions of the whole process (callgrind, one thread, %dx%d):\n" % (cg["size"], cg["size"]))
        L.append("| variant | instructions | ratio |\n|---|---|---|")
        for row in cg["rows"]:
            L.append("| %s | %.4g | %.3fx |" % (row["variant"], row["total_ir"], row["total_ratio"]))
    L.append("")


def spectral_report(L, results):
    """Section spectral: its cost at equal samples, the samples for equal noise, a Lytro-class crop."""
    r = results["spectral"]
    L.append("## Spectral sampling (`--only spectral`)\n")
    L.append("`spectral N` (docs/spectral.md) on the benchmark scene through a made-up 53 mm triplet whose glass"
             " disperses (V_d 58, 30, 58) at f/5.6, with a plenoptic 1.0 array of dispersing microlenses (hexagonal,"
             " 0.1 mm pitch, f = d = 0.56 mm, V_d 58), 10 um pixels, %dx%d, %d interleaved runs, POV-Ray's trace"
             " time; CPU time is the whole process's (it includes the set-up of one camera per band).\n"
             % (r["size"][0], r["size"][1], r["runs"]))
    L.append("| variant | trace, s (median) | ratio | CPU, s | CPU ratio | peak RSS, MiB |\n|---|---|---|---|---|---|")
    for row in r["rows"]:
        L.append("| %s | %.2f | %.3fx | %.2f | %.3fx | %.0f |" % (row["variant"], row["median_trace_s"], row["ratio"],
                                                               row["cpu_s"], row["cpu_ratio"], row["peak_rss_mib"]))
    cg = r.get("callgrind")
    if cg:
        L.append("\nInstructions of the whole process (callgrind, one thread, %dx%d):\n" % (cg["size"], cg["size"]))
        L.append("| variant | instructions | ratio |\n|---|---|---|")
        for row in cg["rows"]:
            L.append("| %s | %.4g | %.3fx |" % (row["variant"], row["total_ir"], row["total_ratio"]))
    n = r["noise"]
    L.append("\n**Noise against samples** (%dx%d): the RMSE of each render against a reference of %d samples of"
             " its own kind (the dispersing lens's spectral picture is not the d line's):\n"
             % (n["size"][0], n["size"][1], n["reference_samples"]))
    L.append("| render | samples | RMSE |\n|---|---|---|")
    for row in n["rows"]:
        L.append("| %s | %d | %.5f |" % (row["variant"], row["samples"], row["rmse"]))
    needed = n["spectral_samples_for_plain_16_noise"]
    L.append("\nSamples `spectral 8` needs for the noise of 16 samples without it (log-log interpolation): %s.\n"
             % ("%.0f" % needed if needed else "beyond the counts measured"))
    c = r["lytro_crop"]
    L.append("**Lytro-class crop through the dispersing lens** (%dx%d pixels of 1.4 um, hexagonal 20 um microlenses,"
             " f/5.6 matched, 16 samples, one run each, the whole process):\n" % (c["size"][0], c["size"][1]))
    L.append("| variant | wall, s | CPU, s | peak RSS, MiB |\n|---|---|---|---|")
    for row in c["rows"]:
        L.append("| %s | %.1f | %.1f | %.0f |" % (row["variant"], row["wall_s"], row["cpu_s"], row["peak_rss_mib"]))
    L.append("")


def real_lens_report(L, results):
    """Section real_lens (and fullsize_real_lens): pass fractions, cost against the thin and thick lens."""
    L.append("## Real main lens (`--only real_lens`, `--only fullsize_real_lens`)\n")
    for e in (results.get("real_lens") or {}).get("lenses", []):
        w, h, px = e["sensor"]
        L.append("`lenses/%s` (docs/real-lenses.md) at f/%g, focused at %g m: EFL %.3f mm, working"
                 " f-number %.3f. Camera: %gx%g mm sensor (%dx%d pixels of %g um), without an array and with a"
                 " plenoptic 1.0 array (hexagonal, pitch %g mm, thin microlenses f = d = %.4f mm, matched to the"
                 " working f-number); the thin lens compared has the same EFL and f-number, `thick_lens` is the"
                 " prescription's paraxial equivalent.\n" % (e["lens_file"], e["f_number"], e["focus_distance"],
                 e["efl_mm"], e["working_f_number"], w * px, h * px, w, h, px * 1000, e["pitch_mm"], e["array_focal_mm"]))
        L.append("**Pass fractions** (counts, not timings): of the camera rays `generate_ray` makes for a pixel"
                 " (the camera's own samples, `make_sample`, %d per pixel unless the table says otherwise), the"
                 " fraction that passes the lens;"
                 " for the pixel itself and for a patch of pixels there (16x16 without an array, two microlens"
                 " pitches square with one: with an array a single pixel lies at a microimage's centre or"
                 " between microimages, so the patch is the figure). *Without bounds*: the same aperture samples"
                 " spread uniformly over the rear element's clear aperture (pbrt's RealisticCamera before its"
                 " exit-pupil bounds) instead of over the pupil-bounds disc. The wasted fraction is 1 minus the"
                 " pass fraction. From `source/bench/pass_fractions.cpp`.\n" % e["count_samples"])
        L.append("| camera | f-number | samples per pixel | place | field radius, mm | pixel: passes | patch |"
                 " patch: passes | patch: wasted | patch without bounds: passes | patch without bounds: wasted |"
                 "\n|---|---|---|---|---|---|---|---|---|---|---|")
        for cam, d in e["counts"].items():
            for p in d["places"]:
                pc, bc = p["pixel_counts"], p["patch_counts"]
                ub = "unbounded_pass_fraction" in bc
                L.append("| %s | %g | %d | %s | %.2f | %s | %dx%d px | %s | %s | %s | %s |" % (
                    cam, d["f_number"], d["samples"], p["place"], p["field_radius_mm"], pct(pc["pass_fraction"]),
                    d["patch"], d["patch"],
                    pct(bc["pass_fraction"]), pct(1 - bc["pass_fraction"]),
                    pct(bc["unbounded_pass_fraction"]) if ub else "-",
                    pct(1 - bc["unbounded_pass_fraction"]) if ub else "-"))
        L.append("")
        cams = [c for c in ("no array", "no array, smaller stop", "plenoptic 1.0", "plenoptic 1.0, thick_lens")
                if c in e["counts"]]
        if cams:
            base = e["counts"][cams[0]]
            L.append("Along the centre row (patches from the axis to the sensor's edge; light stops at %.2f mm,"
                     " where the pupil bounds find none passing):\n" % base["light_field_radius_mm"])
            head = ["field radius, mm"]
            for c in cams:
                label = "%s (f/%g)" % (c, e["counts"][c]["f_number"])
                head.append(label)
                if c.startswith("no array"):
                    head.append(label + ", without bounds")
            L.append("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
            for k, p in enumerate(base["profile"]):
                cells = ["%.2f" % p["field_radius_mm"]]
                for c in cams:
                    q = e["counts"][c]["profile"][k]["patch_counts"]
                    cells.append(pct(q["pass_fraction"]))
                    if c.startswith("no array"):
                        cells.append(pct(q["unbounded_pass_fraction"]))
                L.append("| " + " | ".join(cells) + " |")
            L.append("")
        L.append("Commands (the program is built with the optics core, `build/source/plenoptic/`):\n")
        for cam, d in e["counts"].items():
            L.append("- %s: `%s`" % (cam, d["command"]))
        L.append("")
        c = e.get("cost")
        if c:
            L.append("**Cost**: benchmark scene (`benchmarks/scene.inc`), %dx%d, %d samples for every camera,"
                     " %d interleaved runs (the order rotating every round); ratios to the thin lens of the same"
                     " array, ratio of medians and median of the ratios of each run to the thin-lens run of its"
                     " round. CPU time: user + system, minus a 16x16 render of the same scene (start-up and"
                     " parsing). `microimage_centres off` for every camera: the renders are compared (the"
                     " full-size table below times the centres).\n" % (c["size"][0], c["size"][1], c["samples"], c["runs"]))
            L.append("| camera | trace time, s (median) | ratio to thin | median paired ratio to thin |"
                     " CPU time for the render, s | CPU ratio to thin | peak RSS, MiB |\n|---|---|---|---|---|---|---|")
            for r in c["rows"]:
                L.append("| %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.1f |" % (
                    r["camera"], r["median_s"], r["ratio_to_thin"], r["median_paired_ratio_to_thin"],
                    r["cpu_render_s"], r["cpu_ratio_to_thin"], r["peak_rss_mib"]))
            L.append("")
        g = e.get("callgrind")
        if g:
            L.append("Instruction counts (callgrind, one thread, %dx%d, same field of view, %d samples): as in the"
                     " overhead section, camera instructions per pixel = (inclusive `TracePixel::operator()` -"
                     " inclusive outermost `Trace::TraceRay`) / pixels.\n" % (g["size"][0], g["size"][1], g["samples"]))
            L.append("| camera | total, M instructions | per-pixel work, M instructions | per-pixel work ratio to thin"
                     " | scene, M instructions | scene rays per pixel | camera instructions per pixel |"
                     " camera instructions ratio to thin |\n|---|---|---|---|---|---|---|---|")
            for r in g["rows"]:
                L.append("| %s | %s | %s | %.3f | %s | %.2f | %.0f | %.2f |" % (
                    r["camera"], mega(r["total_ir"]), mega(r["pixel_work_ir"]), r["pixel_work_ratio_to_thin"],
                    mega(r["trace_ray_ir"]), r["trace_ray_calls"] / r["pixels"], r["camera_ir_per_pixel"],
                    r["camera_ratio_to_thin"]))
            L.append("")
    f = results.get("fullsize_real_lens")
    if f:
        L.append("**Lytro-class raw through the real lens** (`--only fullsize_real_lens`): the full-size section's"
                 " camera (%dx%d pixels of 1.4 um, hexagonal 20 um f/2 microlenses, benchmark scene) at %d samples,"
                 " the main lens at f/%g; one run each, interleaved. *Whole process*: povray on the clock, start-up,"
                 " parsing, trace and what the camera writes after the trace (metadata; behind the traced lens also"
                 " `<image>.microimages.csv`, the microimage centres of every lens in the picture).\n"
                 % (f["size"][0], f["size"][1], f["samples"], f["rows"][0]["f_number"] if f["rows"] else 0))
        L.append("| main lens | EFL, mm | trace time, s | ratio to thin | CPU time, s | whole process, s | peak RSS, MiB |"
                 "\n|---|---|---|---|---|---|---|")
        for r in f["rows"]:
            L.append("| %s, `%s` | %.3f | %.1f | %.3f | %.1f | %s | %.0f |" % (
                r["camera"], r["lens_file"], r["efl_mm"], r["median_s"], r["ratio_to_thin"], r["cpu_s"],
                fixed(r.get("wall_s"), 1), r["peak_rss_mib"]))
        L.append("")


def write_report(results, path, plots, results_path):
    """BENCHMARKS.md from results.json: every figure with the command that reproduces it."""
    L = []
    L.append("# Benchmarks\n")
    L.append("Every figure here comes from `tools/bench` (results in `%s`;" % report_path(results_path, path))
    L.append("one section alone: `tools/bench --only SECTION`). Times are medians of %d runs (the overhead"
             " section: of its own count, at least 9) of POV-Ray's own" % results.get("runs", 0))
    L.append("*Trace Time* (its fixed start-up of about 0.5 s excluded); compared variants ran interleaved in")
    L.append("one session. Peak memory is the process's maximum resident set. Timings are never asserted in")
    L.append("tests; CI only runs `tools/bench --quick`.\n")
    L.append("Machine: %s.\n" % results.get("machine", "?"))
    if "build" in results:
        b = results["build"]
        L.append("## Build and test times\n")
        L.append("`tools/bench --only build` (ccache off, Ninja, 2 jobs):\n")
        L.append("| what | seconds |\n|---|---|")
        L.append("| clean build of POV-Ray and the camera | %.0f |" % b["clean_s"])
        L.append("| rebuild after touching `source/plenoptic/camera/rays.cpp` (median of 3) | %.1f |" % b["rebuild_after_touch_s"])
        L.append("")
    if "overhead" in results:
        o = results["overhead"]
        L.append("## Camera overhead (`--only overhead`)\n")
        L.append("Benchmark scene (`benchmarks/scene.inc`), %dx%d, one ray per pixel, same field of view;"
                 " %s interleaved runs, perspective rendered between the two others in every round. The"
                 " paired ratio divides each run by the perspective run rendered right next to it; its"
                 " median is robust to the slow drift of a shared machine.\n"
                 % (o["size"], o["size"], o.get("runs", results.get("runs", "?"))))
        L.append("| camera | trace time, s (median) | ratio of medians to perspective | median of paired ratios"
                 " | fastest run, s | ratio of fastest runs | peak RSS, MiB | RSS - perspective, MiB |"
                 "\n|---|---|---|---|---|---|---|---|")
        fastest_base = min(next(r for r in o["rows"] if r["camera"] == "perspective")["runs_s"])
        for r in o["rows"]:
            L.append("| %s | %.3f | %.3f | %s | %.3f | %.3f | %.1f | %+.1f |" % (r["camera"], r["median_s"], r["ratio"],
                     fixed(r.get("median_paired_ratio")), min(r["runs_s"]), min(r["runs_s"]) / fastest_base,
                     r["peak_rss_mib"], r["rss_minus_perspective_mib"]))
        if all("cpu_ratio" in r for r in o["rows"]):
            L.append("\nCPU time of the same runs (user + system, all threads; medians, minus the CPU time of a"
                     " 16x16 render of the same scene, i.e. start-up and parsing). The clock above also counts the"
                     " time the virtual machine's host lends the cores to others; CPU time does not, so it is the"
                     " steadier measure of the work done here.\n")
            L.append("| camera | CPU time for the render, s | ratio to perspective |\n|---|---|---|")
            for r in o["rows"]:
                L.append("| %s | %.3f | %.3f |" % (r["camera"], r["cpu_render_s"], r["cpu_ratio"]))
        L.append("")
    if results.get("overhead_callgrind"):
        o = results["overhead_callgrind"]
        L.append("Instruction counts of the same cameras (callgrind, one thread, %dx%d; these repeat exactly"
                 " whatever the machine does). Per-pixel work is the inclusive count of"
                 " `TracePixel::operator()` (everything done for the pixels), scene the inclusive count of"
                 " the outermost `Trace::TraceRay` (the rays traced into the scene, and what they cost);"
                 " camera instructions per pixel = (per-pixel work - scene) / pixels.\n" % (o["size"], o["size"]))
        L.append("| camera | total, M instructions | total ratio to perspective | per-pixel work, M instructions"
                 " | per-pixel work ratio to perspective | scene, M instructions | scene rays per pixel"
                 " | camera instructions per pixel |\n|---|---|---|---|---|---|---|---|")
        for r in o["rows"]:
            L.append("| %s | %s | %.4f | %s | %.4f | %s | %.3f | %.0f |" % (
                r["camera"], mega(r["total_ir"]), r["total_ratio"], mega(r["pixel_work_ir"]), r["pixel_work_ratio"],
                mega(r["trace_ray_ir"]), r["trace_ray_calls"] / r["pixels"], r["camera_ir_per_pixel"]))
        L.append("")
    if "lenses" in results:
        o = results["lenses"]
        L.append("## Cost against lens count (`--only lenses`)\n")
        L.append("10^2, 10^4 and 10^6 lenses over the same %dx%d sensor (10 um pixels), 1 sample. The fraction"
                 " of pixels that receive light changes with the lens count when there is a main lens (round"
                 " microimages in square cells at 100 lenses, about one pixel per lens at 10^6), and a dark"
                 " pixel traces no scene ray: *pixels lit* counts the pixels that are not black in a render of"
                 " a white world, and *time per lit pixel* is the trace time divided by their number.\n"
                 % (o["size"], o["size"]))
    for key in ("lenses", "lenses_empty_scene", "lenses_array", "lenses_array_empty_scene"):
        if key not in results:
            continue
        o = results[key]
        scene = o.get("scene", "empty" if key.endswith("empty_scene") else "benchmark")
        camera = o.get("camera", "thin main lens + rectangular pinhole array")
        if scene == "empty":
            L.append("%s, empty scene (a plain background: every ray costs the same and almost nothing, so what"
                     " remains is the camera's own cost):\n" % (camera[0].upper() + camera[1:]))
        else:
            L.append("%s, benchmark scene:\n" % (camera[0].upper() + camera[1:]))
        lens_table(L, o)
    if results.get("lenses_callgrind"):
        o = results["lenses_callgrind"]
        L.append("Instruction counts (callgrind, one thread, %s scene, %dx%d): camera instructions per pixel ="
                 " (inclusive `TracePixel::operator()` - inclusive outermost `Trace::TraceRay`) / pixels, which"
                 " leaves out the scene whatever fraction of the pixels is lit.\n" % (o["scene"], o["size"], o["size"]))
        L.append("| camera | lenses | scene rays per pixel | camera instructions per pixel | ratio to 100 lenses"
                 " | total, M instructions |\n|---|---|---|---|---|---|")
        for fam in o["families"].values():
            for r in fam["rows"]:
                L.append("| %s | %d | %.3f | %.0f | %.4f | %s |" % (fam["camera"], r["lenses"], r["traced_per_pixel"],
                         r["camera_ir_per_pixel"], r["camera_ratio_to_100"], mega(r["total_ir"])))
        L.append("")
    if "trade" in results:
        t = results["trade"]
        L.append("## Speed against accuracy (`--only trade`)\n")
        L.append("%dx%d, error against a %d-sample render of the same camera (RMSE over linear RGB, PSNR"
                 " with peak 1)." % (t["size"][0], t["size"][1], t["reference_samples"]))
        trade_plots = [p for p in plots if os.path.basename(p) == "trade.png"]
        if trade_plots:
            L.append("\n![trade](%s)\n" % report_path(trade_plots[0], path))
        for label, points in t["configs"].items():
            L.append("### %s\n" % label)
            L.append("| form | time, s | RMSE | PSNR, dB | fixed-count time for the same RMSE, s | adaptive / fixed |"
                     " oracle allocation bound |\n|---|---|---|---|---|---|---|")
            for p in points:
                L.append("| `%s` | %.3f | %.4f | %.1f | %s | %s | %s |" % (p["text"], p["median_s"], p["rmse"], p["psnr_db"],
                         fmt(p.get("fixed_time_for_same_error_s")), fmt(p.get("time_ratio_to_fixed")),
                         fmt(p.get("allocation_bound"))))
            L.append("")
        L.append("*Oracle allocation bound*: the fraction of a fixed count's samples with which a per-pixel adaptive"
                 " scheme that knew every pixel's error could reach the same RMSE, (mean e)^2 / mean(e^2) over the"
                 " per-pixel errors e of that fixed-count render (errors falling as 1/sqrt(samples)). No stopping"
                 " rule does better than its oracle.\n")
    if "dark" in results:
        d = results["dark"]
        L.append("## Pixels no light reaches (`--only dark`)\n")
        L.append("Lytro-class camera (1.4 um pixels, 20 um hexagonal pitch, f/2), %dx%d, 4 samples; %.1f%% of its"
                 " pixels receive no light (black in a white scene)." % (d["size"], d["size"], 100 * d["dark_pixel_fraction"]))
        if d.get("lit_sample_fraction") is not None:
            L.append("Of the samples, %.1f%% pass the apertures (mean pixel value of the white-scene render at %d"
                     " samples: a lit sample returns 1, a blocked one 0). A blocked sample traces no scene ray, so,"
                     " *as an estimate from the lit fraction* (every traced sample costing the same), the"
                     " Lytro-class render leaves out %s s of scene rays (its time x (1 / lit fraction - 1))."
                     % (100 * d["lit_sample_fraction"], d.get("white_samples", 16), fixed(d.get("estimated_untraced_s"))))
        L.append("The measured comparison traces every sample of every pixel over the same sensor.\n")
        L.append("| render | trace time, s |\n|---|---|")
        for r in d["rows"]:
            L.append("| %s | %.3f |" % (r["camera"], r["median_s"]))
        L.append("")
    if "threads" in results:
        t = results["threads"]
        L.append("## Threads (`--only threads`)\n")
        L.append("| threads | trace time, s |\n|---|---|\n| 1 | %.3f |\n| 2 | %.3f |\n\nSpeed-up %.2fx (%dx%d plenoptic 1.0, 4 samples).\n"
                 % (t["one_thread_s"], t["two_threads_s"], t["speedup"], t["size"], t["size"]))
    if "fullsize" in results:
        f = results["fullsize"]
        L.append("## Full-size raw (`--only fullsize`)\n")
        L.append("Lytro Illum-class sensor, %dx%d (%.1f Mpx), 1 sample, benchmark scene: trace time %.1f s (median of %d),"
                 " peak RSS %.0f MiB.\n" % (f["size"][0], f["size"][1], f["size"][0] * f["size"][1] / 1e6, f["median_s"], f["runs"], f["peak_rss_mib"]))
    if results.get("real_lens") or results.get("fullsize_real_lens"):
        real_lens_report(L, results)
    if results.get("realism"):
        realism_report(L, results)
    if results.get("spectral"):
        spectral_report(L, results)
    if results.get("arrays"):
        from .arrays import arrays_report
        arrays_report(L, results)
    if results.get("refracting"):
        from .refracting import refracting_report
        refracting_report(L, results)
    if results.get("dataset"):
        dataset_report(L, results)
    analysis = os.path.join(ROOT, "benchmarks", "analysis.md")
    if os.path.exists(analysis):
        with open(analysis) as fh:
            L.append(fh.read())
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as fh:
        fh.write("\n".join(L))


def plot(results, outdir):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        log("matplotlib missing: no plots")
        return []
    files = []
    if "trade" in results:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for label, points in results["trade"]["configs"].items():
            fixed = [p for p in points if p["form"] == "fixed"]
            adapt = [p for p in points if p["form"] == "adaptive"]
            line, = ax.loglog([p["median_s"] for p in fixed], [p["rmse"] for p in fixed], "o-", label=label + " (fixed)")
            if adapt:
                ax.loglog([p["median_s"] for p in adapt], [p["rmse"] for p in adapt], "s--", color=line.get_color(),
                          label=label + " (adaptive)")
            for p in fixed:
                ax.annotate(str(p["samples"]), (p["median_s"], p["rmse"]), fontsize=7, xytext=(3, 3),
                            textcoords="offset points")
        ax.set_xlabel("render time, s (median)")
        ax.set_ylabel("RMSE against %d-sample reference" % results["trade"]["reference_samples"])
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        ax.set_title("Speed/accuracy trade (%dx%d)" % tuple(results["trade"]["size"]))
        fig.tight_layout()
        path = os.path.join(outdir, "trade.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        files.append(path)
    return files
