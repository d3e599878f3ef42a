# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section lenses: cost against the number of microlenses (10^2, 10^4, 10^6)."""
import math

from .callgrind import have_callgrind
from .runner import EMPTY_WORLD, thin_main
from .util import LOCATION, log


LENS_COUNTS = (10**2, 10**4, 10**6)

# Two families of camera with 10^2, 10^4 and 10^6 lenses over the same sensor. With a main lens
# the lit fraction of the pixels changes with the lens count (round microimages in square cells
# at 100 lenses, about one pixel per lens at 10^6); without one (a camera array) every pixel is lit.
LENS_FAMILIES = {
    "thin": {"camera": "thin main lens (f/4) + rectangular pinhole array",
             "keys": ("lenses", "lenses_empty_scene")},
    "array": {"camera": "camera array: no main lens, rectangular pinhole array",
              "keys": ("lenses_array", "lenses_array_empty_scene")},
}


def lens_camera(family, count, size, px=0.01):
    pitch = size * px / round(math.sqrt(count))
    array = "microlens_array { rectangular pitch %.12g pinhole distance %.12g }" % (pitch, 4 * pitch)
    main = thin_main() + " " if family == "thin" else ""
    return "plenoptic %s %s%s sensor { pixel_size %g } samples 1" % (LOCATION, main, array, px)


def section_lenses(b, size, count_size, results):
    for family, spec in LENS_FAMILIES.items():
        cameras = {n: lens_camera(family, n, size) for n in LENS_COUNTS}
        log("lens count (%s): pixels that receive light" % spec["camera"])
        lit = {n: float((b.white("lens_white_%s_%d" % (family, n), cam, size, size).max(axis=2) > 0).mean())
               for n, cam in cameras.items()}
        for key, world in zip(spec["keys"], (None, EMPTY_WORLD)):
            section_lenses_in(b, size, results, key, world, spec["camera"], cameras, lit)
    if count_size and have_callgrind():
        out = {}
        for family, spec in LENS_FAMILIES.items():
            log("lens count (%s): instruction counts (callgrind), empty scene, %dx%d"
                % (spec["camera"], count_size, count_size))
            rows = []
            for n in LENS_COUNTS:
                c = b.count(b.scene("lens_cg_%d" % n, lens_camera(family, n, count_size), EMPTY_WORLD),
                            count_size, count_size)
                rows.append(dict(c, lenses=n, traced_per_pixel=c["trace_ray_calls"] / c["pixels"]))
                log("  %d lenses: camera %.0f instructions per pixel, %.3f scene rays per pixel"
                    % (n, c["camera_ir_per_pixel"], rows[-1]["traced_per_pixel"]))
            for r in rows:
                r["camera_ratio_to_100"] = r["camera_ir_per_pixel"] / rows[0]["camera_ir_per_pixel"]
            out[family] = {"camera": spec["camera"], "rows": rows}
        results["lenses_callgrind"] = {"size": count_size, "scene": "empty", "families": out}
    elif count_size:
        log("lens count: valgrind not installed, no instruction counts")
        results["lenses_callgrind"] = None


def section_lenses_in(b, size, results, key, world, camera, cameras, lit):
    log("lens count (%s, %s scene): 10^2, 10^4, 10^6 lenses at %dx%d"
        % (camera, "empty" if world else "benchmark", size, size))
    variants = {n: b.scene("lens_%d" % n, cam, world) for n, cam in cameras.items()}
    res = b.compare(variants, size, size)
    rows = []
    for n, (t, m, ts) in res.items():
        lit_pixels = lit[n] * size * size
        rows.append({"lenses": n, "lit_pixel_fraction": lit[n], "median_s": t, "peak_rss_mib": m, "runs_s": ts,
                     "us_per_lit_pixel": 1e6 * t / lit_pixels if lit_pixels else None})
    for r in rows:
        # POV-Ray's trace time has millisecond steps: a quick run's 100 lenses may take 0.000 s.
        r["ratio_to_100"] = r["median_s"] / rows[0]["median_s"] if rows[0]["median_s"] else None
        base = rows[0]["us_per_lit_pixel"]
        r["per_lit_pixel_ratio_to_100"] = r["us_per_lit_pixel"] / base if base and r["us_per_lit_pixel"] else None
    results[key] = {"size": size, "camera": camera, "scene": "empty" if world else "benchmark", "rows": rows}
