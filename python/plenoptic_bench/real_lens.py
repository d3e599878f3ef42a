# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section real_lens: a prescription main lens, traced surface by surface, against the
thin lens of the same effective focal length and f-number and against its paraxial equivalent
(`thick_lens`).

- Pass fractions (counts, not timings): the program plenoptic_pass_fractions (built with the
  optics core, source/plenoptic) builds the camera's model as the parser would and asks
  generate_ray for the camera's own samples of the central, an edge and a corner pixel (and of
  patches of pixels there, and along the centre row); without an array it also counts what
  sampling the rear element's whole clear aperture (pbrt before its exit-pupil bounds) would pass.
- Cost: renders of the benchmark scene at equal samples, interleaved, with CPU time and callgrind
  instruction counts beside POV-Ray's trace time, without an array and with a plenoptic 1.0 array.
- The Lytro-class raw of the fullsize section at 16 samples through the real lens, against the
  same camera with the thin lens of the same focal length and f-number (--fullsize-real, or
  --only fullsize_real_lens: it takes several minutes a render).
"""
import json
import os
import statistics
import subprocess

from .callgrind import have_callgrind
from .util import LOCATION, ROOT, log

# The prescriptions in lenses/ that the section measures, with the f-number it renders them at (the
# lens's own, wide open). Add a lens here when lenses/ gains one.
LENSES = [("wide_angle_22mm_laikin_f3.5.dat", 3.5)]
FOCUS = 2.5  # scene units (m) in front of the lens: the benchmark scene's subject

# The camera of the counts and the renders: an 18 x 12 mm sensor (inside the Laikin lens's
# image circle, where some light still reaches the corners) of 25 um pixels; the plenoptic 1.0
# array has 0.25 mm hexagonal microlenses (10 pixels) matched to the lens's working f-number.
SENSOR = (720, 480, 0.025)
PITCH = 0.25
SAMPLES = 16  # the camera's default where an aperture is sampled
COUNT_SAMPLES = 256  # samples per pixel for the counts (the same sequence, at that count)

# The fullsize section's Lytro-class camera (1.4 um pixels, 20 um hexagonal f/2 microlenses). The
# Laikin lens cannot deliver f/2 (its element rims limit the axial beam beyond f/2.743 at this
# focus, and the camera refuses f_number 2 there); at f/2.8 its microimages are smaller than the
# f/2 cells, which the cost comparison with the thin lens of the same f-number does not mind.
LYTRO_ARRAY = "microlens_array { hexagonal pitch 0.02 focal_length 0.04 distance 0.04 }"
LYTRO_F_NUMBER = 2.8
LYTRO_PIXEL = 0.0014


def pass_fractions_program(povray):
    """plenoptic_pass_fractions in the build tree of the povray binary."""
    return os.path.join(os.path.dirname(povray), "source", "bench", "plenoptic_pass_fractions")


def count_passes(program, lens_file, f_number, sensor, samples, array=None, thick=False):
    cmd = [program, "--lens-file", lens_file, "--f-number", repr(f_number), "--focus-distance", repr(FOCUS),
           "--sensor", str(sensor[0]), str(sensor[1]), repr(sensor[2]), "--samples", str(samples)]
    if array == "matched":
        cmd += ["--array-matched", repr(PITCH)]
    elif array:
        cmd += ["--array"] + [repr(x) for x in array]
    if thick:
        cmd.append("--thick")
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    d = json.loads(out)
    # As BENCHMARKS.md shows it: the program by name, the lens file relative to the repository.
    d["command"] = " ".join(["plenoptic_pass_fractions"] + [
        os.path.relpath(a, ROOT) if a == lens_file else a for a in cmd[1:]])
    # The program echoes the lens file as given (an absolute path): results.json is committed and
    # names no path outside the repository.
    if d.get("lens_file") == lens_file:
        d["lens_file"] = os.path.relpath(lens_file, ROOT)
    return d


def prescription_main(lens_path, f_number, thick=False):
    return 'main_lens { lens_file "%s" f_number %g focus_distance %g%s }' % (
        lens_path, f_number, FOCUS, " thick_lens" if thick else "")


def thin_main_of(efl, f_number):
    return "main_lens { thin_lens focal_length %.9g f_number %g focus_distance %g }" % (efl, f_number, FOCUS)


def cameras(lens_path, f_number, efl, array_focal, px):
    """{label: camera} without an array and with the matched plenoptic 1.0 array. The microimage centres
    (written by default behind a traced lens with an array) are off: the renders are compared, and
    the full-size section measures the centres."""
    array = "microlens_array { hexagonal pitch %g focal_length %.9g distance %.9g }" % (PITCH, array_focal, array_focal)
    mains = {"prescription (traced)": prescription_main(lens_path, f_number),
             "thick_lens": prescription_main(lens_path, f_number, thick=True),
             "thin lens, same EFL and f-number": thin_main_of(efl, f_number)}
    out = {}
    for where, arr in (("no array", ""), ("plenoptic 1.0", array + " ")):
        for label, main in mains.items():
            out["%s, %s" % (label, where)] = "plenoptic %s %s %ssensor { pixel_size %g } samples %d microimage_centres off" % (
                LOCATION, main, arr, px, SAMPLES)
    return out


def section_real_lens(b, quick, runs, results):
    program = pass_fractions_program(b.povray)
    if not os.path.exists(program):
        raise RuntimeError("%s not found: build it (tools/build builds it with the optics core)" % program)
    lenses_out = []
    for name, f_number in LENSES:
        lens_path = os.path.join(ROOT, "lenses", name)
        log("real lens: pass fractions of %s at f/%g" % (name, f_number))
        samples = 16 if quick else COUNT_SAMPLES
        counts = {
            "no array": count_passes(program, lens_path, f_number, SENSOR, samples),
            "no array, smaller stop": count_passes(program, lens_path, 5.6, SENSOR, samples),
            "plenoptic 1.0": count_passes(program, lens_path, f_number, SENSOR, samples, array="matched"),
            "plenoptic 1.0, thick_lens": count_passes(program, lens_path, f_number, SENSOR, samples, array="matched",
                                                      thick=True),
            "Lytro-class (fullsize camera)": count_passes(program, lens_path, LYTRO_F_NUMBER, (7728, 5368, LYTRO_PIXEL),
                                                          16, array=(0.02, 0.04, 0.04)),
            "Lytro-class (fullsize camera), thick_lens": count_passes(
                program, lens_path, LYTRO_F_NUMBER, (7728, 5368, LYTRO_PIXEL), 16, array=(0.02, 0.04, 0.04), thick=True),
        }
        base = counts["no array"]
        efl = base["effective_focal_length_mm"]
        array_focal = counts["plenoptic 1.0"]["array"]["focal_length_mm"]
        entry = {"lens_file": name, "f_number": f_number, "focus_distance": FOCUS, "efl_mm": efl,
                 "working_f_number": base["working_f_number"], "sensor": list(SENSOR), "pitch_mm": PITCH,
                 "array_focal_mm": array_focal, "count_samples": samples, "counts": counts}

        # Cost: every camera at equal samples on the benchmark scene, interleaved (the order rotates
        # every round so that no camera always follows the same one).
        w, h, px = (96, 64, SENSOR[2] * SENSOR[0] / 96) if quick else SENSOR
        cams = cameras(lens_path, f_number, efl, array_focal, px)
        variants = {label: b.scene("real_%d" % k, cam) for k, (label, cam) in enumerate(cams.items())}
        labels = list(variants)
        log("real lens: %d cameras at %dx%d, %d samples, %d interleaved runs" % (len(labels), w, h, SAMPLES, runs))
        res = b.compare(variants, w, h, runs=runs, order=lambda r: labels[r % len(labels):] + labels[:r % len(labels)])
        cpu = b.cpu_runs
        b.compare(variants, 16, 16, runs=min(runs, 3))
        startup = {k: statistics.median(v) for k, v in b.cpu_runs.items()}
        rows = []
        for label, (t, m, ts) in res.items():
            where = label.split(", ")[-1]
            thin = "thin lens, same EFL and f-number, " + where
            thin_ts = res[thin][2]
            cpu_render = statistics.median(cpu[label]) - startup[label]
            cpu_thin = statistics.median(cpu[thin]) - startup[thin]
            rows.append({"camera": label, "array": where, "median_s": t, "runs_s": ts, "peak_rss_mib": m,
                         "ratio_to_thin": t / res[thin][0],
                         "median_paired_ratio_to_thin": statistics.median(x / y for x, y in zip(ts, thin_ts)),
                         "cpu_render_s": cpu_render, "cpu_runs_s": cpu[label], "cpu_startup_s": startup[label],
                         "cpu_ratio_to_thin": cpu_render / cpu_thin})
            log("  %s: %.3f s, %.3fx thin (paired %.3f), CPU %.3fx" % (label, t, rows[-1]["ratio_to_thin"],
                rows[-1]["median_paired_ratio_to_thin"], rows[-1]["cpu_ratio_to_thin"]))
        entry["cost"] = {"size": [w, h], "pixel_size_mm": px, "samples": SAMPLES, "runs": runs, "rows": rows}

        if have_callgrind():
            cw, ch = (24, 16) if quick else (120, 80)
            cpx = SENSOR[2] * SENSOR[0] / cw
            log("real lens: instruction counts (callgrind) at %dx%d" % (cw, ch))
            counts_cg = {label: b.count(b.scene("real_cg_%d" % k, cam), cw, ch)
                         for k, (label, cam) in enumerate(cameras(lens_path, f_number, efl, array_focal, cpx).items())}
            crows = []
            for label, c in counts_cg.items():
                where = label.split(", ")[-1]
                thin = counts_cg["thin lens, same EFL and f-number, " + where]
                crows.append(dict(c, camera=label, array=where,
                                  pixel_work_ratio_to_thin=c["pixel_work_ir"] / thin["pixel_work_ir"],
                                  camera_ratio_to_thin=c["camera_ir_per_pixel"] / thin["camera_ir_per_pixel"]))
                log("  %s: camera %.0f instructions per pixel, per-pixel work %.3fx thin"
                    % (label, c["camera_ir_per_pixel"], crows[-1]["pixel_work_ratio_to_thin"]))
            entry["callgrind"] = {"size": [cw, ch], "pixel_size_mm": cpx, "samples": SAMPLES, "rows": crows}
        else:
            log("real lens: valgrind not installed, no instruction counts")
            entry["callgrind"] = None
        lenses_out.append(entry)
    results["real_lens"] = {"lenses": lenses_out}


def section_fullsize_real_lens(b, w, h, results):
    """The fullsize section's Lytro-class raw at 16 samples, through each lens of LENSES at
    LYTRO_F_NUMBER and through the thin lens of the same focal length and f-number; one run
    each, interleaved."""
    program = pass_fractions_program(b.povray)
    rows = []
    for name, _ in LENSES:
        lens_path = os.path.join(ROOT, "lenses", name)
        efl = count_passes(program, lens_path, LYTRO_F_NUMBER, (64, 64, 0.01), 2)["effective_focal_length_mm"]
        cams = {"prescription (traced)": prescription_main(lens_path, LYTRO_F_NUMBER),
                "thin lens, same EFL and f-number": thin_main_of(efl, LYTRO_F_NUMBER)}
        variants = {label: b.scene("fullsize_real_%d" % k, "plenoptic %s %s %s sensor { pixel_size %g } samples 16"
                                   % (LOCATION, main, LYTRO_ARRAY, LYTRO_PIXEL))
                    for k, (label, main) in enumerate(cams.items())}
        log("fullsize through %s: %dx%d, 16 samples" % (name, w, h))
        res = b.compare(variants, w, h, runs=1)
        cpu, wall = b.cpu_runs, b.wall_runs
        thin = res["thin lens, same EFL and f-number"][0]
        for label, (t, m, ts) in res.items():
            rows.append({"lens_file": name, "camera": label, "f_number": LYTRO_F_NUMBER, "efl_mm": efl,
                         "median_s": t, "runs_s": ts, "cpu_s": cpu[label][0], "wall_s": wall[label][0],
                         "peak_rss_mib": m, "ratio_to_thin": t / thin})
            log("  %s: %.1f s (%.3fx thin), CPU %.1f s" % (label, t, t / thin, cpu[label][0]))
    results["fullsize_real_lens"] = {"size": [w, h], "samples": 16, "rows": rows}
