# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section trade: error against time, fixed and adaptive sample counts."""
import math
import statistics

from .runner import read_linear, thin_main
from .util import LOCATION, log


def section_trade(b, size, counts, ref_count, results):
    import numpy as np
    w, h = size
    log("trade: error vs time at %dx%d, reference %d samples" % (w, h, ref_count))
    configs = {
        "plenoptic 1.0, thin-lens microlenses": "hexagonal pitch 0.16 focal_length 0.64 distance 0.64",
        "plenoptic 1.0, pinhole microlenses": "hexagonal pitch 0.16 pinhole distance 0.64",
        "focused 2.0, thin-lens microlenses": "hexagonal pitch 0.16 focal_length 0.64 distance 0.8",
        "focused 2.0 geometry, pinhole microlenses": "hexagonal pitch 0.16 pinhole distance 0.8",
    }
    adaptive = [(4, 256, 1.0 / 128), (4, 256, 1.0 / 1024), (16, 256, 1.0 / 4096), (16, 1024, 1.0 / 16384),
                (64, 1024, 1.0 / 65536)]
    out = {}
    for label, array in configs.items():
        base = "plenoptic %s %s microlens_array { %s } sensor { pixel_size 0.02 }" % (LOCATION, thin_main(), array)
        ref_scene = b.scene("trade_ref", base + " samples %d" % ref_count)
        _, _, ref_png = b.render(ref_scene, w, h, extra=["+WT2"])
        ref = read_linear(ref_png)
        points = []
        forms = [("fixed", n, "samples %d" % n) for n in counts]
        forms += [("adaptive", (lo, hi, v), "samples %d, %d variance %.12g" % (lo, hi, v))
                  for lo, hi, v in adaptive if hi <= max(counts) * 4]
        for kind, n, text in forms:
            scene = b.scene("trade_pt", base + " " + text)
            ts = []
            for r in range(b.runs):
                s, _, png = b.render(scene, w, h)
                ts.append(s)
            img = read_linear(png)
            rmse = float(np.sqrt(np.mean((img - ref) ** 2)))
            psnr = float(20 * math.log10(1.0 / rmse)) if rmse > 0 else float("inf")
            point = {"form": kind, "samples": n, "text": text, "median_s": statistics.median(ts),
                     "rmse": rmse, "psnr_db": psnr, "runs_s": ts}
            if kind == "fixed" and n > 1:
                point["allocation_bound"] = allocation_bound(img, ref)
            points.append(point)
            log("  %s, %s: %.2f s, RMSE %.4f" % (label, text, statistics.median(ts), rmse))
        out[label] = points
    results["trade"] = {"size": [w, h], "reference_samples": ref_count, "configs": out}


def allocation_bound(img, ref):
    """The best any per-pixel adaptive scheme could do against this fixed count, as a fraction of its
    samples: with pixel i's error e_i falling as 1/sqrt(samples), giving pixel i samples in
    proportion to e_i (an oracle that knows every e_i) reaches the same RMSE with
    (mean e)^2 / mean(e^2) of the samples. Real stopping rules only estimate e_i, from few samples."""
    import numpy as np
    e = np.sqrt(np.mean((img - ref) ** 2, axis=2)).ravel()
    square = float(np.mean(e ** 2))
    return float(np.mean(e)) ** 2 / square if square > 0 else None


def fixed_time_for_error(points, err):
    """Time the fixed-count curve needs to reach `err` (log-log interpolation), or None."""
    fixed = sorted([p for p in points if p["form"] == "fixed"], key=lambda p: p["median_s"])
    for a, c in zip(fixed, fixed[1:]):
        if a["rmse"] >= err >= c["rmse"] and a["rmse"] > 0 and c["rmse"] > 0:
            t = math.log(a["rmse"] / err) / math.log(a["rmse"] / c["rmse"])
            return math.exp(math.log(a["median_s"]) + t * (math.log(c["median_s"]) - math.log(a["median_s"])))
    return None
