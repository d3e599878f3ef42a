# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section spectral: what `spectral N` costs at equal samples, the samples it needs to reach the
noise of a render without it, and a Lytro-class crop through a dispersing lens."""
import statistics

import numpy as np

from .callgrind import have_callgrind
from .util import LOCATION, log

# A made-up triplet of about 53 mm (the tests' vignetting triplet) with glass that disperses:
# crown elements V_d 58, the flint V_d 30 (typical catalogue figures of those glass families).
TRIPLET = ("main_lens { prescription {"
           " surface { radius 30 thickness 6 ior 1.6 aperture 24 abbe 58 }"
           " surface { radius -200 thickness 4 ior 1 aperture 24 }"
           " stop { thickness 4 aperture 10 }"
           " surface { radius -40 thickness 2 ior 1.6 aperture 14 abbe 30 }"
           " surface { radius 60 thickness 4 ior 1 aperture 14 }"
           " surface { radius 100 thickness 5 ior 1.6 aperture 18 abbe 58 }"
           " surface { radius -40 thickness 0 ior 1 aperture 18 } } f_number 5.6 focus_distance 2.5 }")
# Plenoptic 1.0 behind it: f-number-matched hexagonal microlenses, 10 um pixels.
ARRAY = "microlens_array { hexagonal pitch 0.1 focal_length 0.56 distance 0.56 abbe 58 } sensor { pixel_size 0.01 }"
# The Lytro-class array (20 um hexagonal pitch, 1.4 um pixels) behind the same lens.
LYTRO_ARRAY = ("microlens_array { hexagonal pitch 0.02 focal_length 0.112 distance 0.112 abbe 58 } "
               "sensor { pixel_size 0.0014 }")


def camera(array, samples, bands=0):
    return "plenoptic %s %s %s samples %d%s" % (LOCATION, TRIPLET, array, samples,
                                               " spectral %d" % bands if bands else "")


def rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)))


def section_spectral(b, size, runs, noise_size, reference_samples, crop, count_size, results):
    w, h = size
    log("spectral: cost at equal samples, %dx%d, %d interleaved runs" % (w, h, runs))
    variants = {"without spectral, 16 samples": b.scene("spectral_plain", camera(ARRAY, 16)),
                "spectral 8, 16 samples": b.scene("spectral_8", camera(ARRAY, 16, 8)),
                "spectral 16, 16 samples": b.scene("spectral_16", camera(ARRAY, 16, 16))}
    res = b.compare(variants, w, h, runs=runs)
    cpu = {k: statistics.median(v) for k, v in b.cpu_runs.items()}
    base = "without spectral, 16 samples"
    rows = [{"variant": k, "median_trace_s": t, "ratio": t / res[base][0], "cpu_s": cpu[k],
             "cpu_ratio": cpu[k] / cpu[base], "peak_rss_mib": m, "runs_s": ts} for k, (t, m, ts) in res.items()]
    for r in rows:
        log("  %s: %.2f s (%.3fx), CPU %.2f s" % (r["variant"], r["median_trace_s"], r["ratio"], r["cpu_s"]))
    out = {"size": [w, h], "runs": runs, "rows": rows}

    # Noise: each against its own reference of reference_samples samples (the dispersing lens's
    # picture differs from the d line's, so the spectral renders have a spectral reference).
    nw, nh = noise_size
    log("spectral: noise at %dx%d against references of %d samples" % (nw, nh, reference_samples))
    _, _, plain_ref = b.render(b.scene("noise_plain_ref", camera(ARRAY, reference_samples)), nw, nh, extra=["+WT2"])
    plain_ref = b_read(plain_ref)
    _, _, spec_ref = b.render(b.scene("noise_spec_ref", camera(ARRAY, reference_samples, 8)), nw, nh, extra=["+WT2"])
    spec_ref = b_read(spec_ref)
    noise = []
    for samples in (16,):
        _, _, p = b.render(b.scene("noise_plain_%d" % samples, camera(ARRAY, samples)), nw, nh, extra=["+WT2"])
        noise.append({"variant": "without spectral", "samples": samples, "rmse": rmse(b_read(p), plain_ref)})
    for samples in (8, 16, 32, 64, 128):
        _, _, p = b.render(b.scene("noise_spec_%d" % samples, camera(ARRAY, samples, 8)), nw, nh, extra=["+WT2"])
        noise.append({"variant": "spectral 8", "samples": samples, "rmse": rmse(b_read(p), spec_ref)})
    for n in noise:
        log("  %s, %d samples: RMSE %.5f" % (n["variant"], n["samples"], n["rmse"]))
    target = noise[0]["rmse"]
    spectral_points = [n for n in noise if n["variant"] == "spectral 8"]
    needed = None
    for a, c in zip(spectral_points, spectral_points[1:]):
        if a["rmse"] >= target >= c["rmse"]:
            # log-log interpolation between the two counts that bracket the target
            t = (np.log(a["rmse"]) - np.log(target)) / (np.log(a["rmse"]) - np.log(c["rmse"]))
            needed = float(np.exp(np.log(a["samples"]) + t * (np.log(c["samples"]) - np.log(a["samples"]))))
            break
    out["noise"] = {"size": [nw, nh], "reference_samples": reference_samples, "rows": noise,
                    "spectral_samples_for_plain_16_noise": needed}

    # The Lytro-class crop through the dispersing lens, once each, the whole process's clock.
    cw, ch = crop
    log("spectral: Lytro-class crop %dx%d through the dispersing triplet" % (cw, ch))
    b.use_trace_time = False
    try:
        crop_res = b.compare({"without spectral, 16 samples": b.scene("lytro_plain", camera(LYTRO_ARRAY, 16)),
                              "spectral 8, 16 samples": b.scene("lytro_spec", camera(LYTRO_ARRAY, 16, 8))},
                             cw, ch, runs=1)
    finally:
        b.use_trace_time = True
    crop_cpu = {k: statistics.median(v) for k, v in b.cpu_runs.items()}
    out["lytro_crop"] = {"size": [cw, ch], "rows": [
        {"variant": k, "wall_s": t, "cpu_s": crop_cpu[k], "peak_rss_mib": m} for k, (t, m, ts) in crop_res.items()]}
    for r in out["lytro_crop"]["rows"]:
        log("  crop %s: %.1f s, CPU %.1f s, %.0f MiB" % (r["variant"], r["wall_s"], r["cpu_s"], r["peak_rss_mib"]))

    if count_size and have_callgrind():
        log("spectral: instruction counts (callgrind) at %dx%d" % (count_size, count_size))
        counts = {k: b.count(v, count_size, count_size) for k, v in variants.items()}
        out["callgrind"] = {"size": count_size, "rows": [
            {"variant": k, "total_ir": c["total_ir"], "total_ratio": c["total_ir"] / counts[base]["total_ir"]}
            for k, c in counts.items()]}
    results["spectral"] = out


def b_read(path):
    from .runner import read_linear
    return np.asarray(read_linear(path), dtype=np.float64)
