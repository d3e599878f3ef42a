#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Writes the fuzzer's seed corpus (fuzz/corpus/*.bin) in the byte format that decode() in
fuzz/plenoptic_fuzz.cpp reads: every submodel with sensible values, the singular-looking
set-ups (d = f, D = F, far focus), extremes, and refusals (NaN, infinities, both or neither of
two alternatives, out-of-range samples). Doubles and ints are written raw (tag 1), so this file
needs no copy of the fuzzer's table of special values.

    python3 fuzz/make_corpus.py            # rewrites fuzz/corpus/
"""
import os
import struct

NAN = float("nan")
INF = float("inf")

MAIN_TYPES = {"none": 0, "pinhole": 1, "thin_lens": 2}
GRIDS = {"none": 0, "rectangular": 1, "hexagonal": 2}
LENSES = {"pinhole": 0, "thin_lens": 1}


def real(x):
    return bytes([1]) + struct.pack("<d", x)


def integer(n):
    return bytes([1]) + struct.pack("<i", n)


def flag(b):
    return bytes([1 if b else 0])


def byte(v):
    return bytes([v & 0xFF])


def encode(c):
    """c: dict of the camera; missing keys are absent values (flag 0)."""
    out = real(c.get("mm_per_unit", 1000.0))
    main = c.get("main")
    out += flag(main is not None)
    main = main or {}
    out += byte(MAIN_TYPES[main.get("type", "none")])
    for key, default in (("focal_length", 50.0), ("f_number", 4.0), ("aperture", 12.5),
                         ("focus_distance", 2.5), ("distance", 52.0)):
        out += flag(key in main) + real(main.get(key, default))
    array = c.get("array")
    out += flag(array is not None)
    array = array or {}
    out += byte(GRIDS[array.get("grid", "none")])
    out += flag("pitch" in array) + real(array.get("pitch", 0.5))
    lens = array.get("lens")
    out += flag(lens is not None) + byte(LENSES[lens or "pinhole"])
    fl = array.get("focal_lengths", [])
    out += byte(len(fl))
    for k in range(3):
        out += real(fl[k] if k < len(fl) else 2.0)
    out += flag("distance" in array) + real(array.get("distance", 2.0))
    for v in array.get("rotate", (0.0, 0.0, 0.0)):
        out += real(v)
    for v in array.get("translate", (0.0, 0.0, 0.0)):
        out += real(v)
    sensor = c.get("sensor", {})
    for v in sensor.get("pixel_size", (0.01, 0.01)):
        out += real(v)
    for v in sensor.get("offset", (0.0, 0.0)):
        out += real(v)
    s = c.get("samples", {})
    out += integer(s.get("samples", 4))
    out += flag(s.get("adaptive", False))
    out += integer(s.get("min", 0)) + integer(s.get("max", 0))
    out += real(s.get("confidence", 0.9)) + real(s.get("variance", 1.0 / 128))
    w, h = c.get("image", (32, 24))
    out += byte(w - 1) + byte(h - 1)
    pixels = c.get("pixels", [(0, 0), (w // 2, h // 2), (w - 1, h - 1)])
    out += byte(len(pixels) - 1)
    for i, j in pixels:
        out += byte(i) + byte(j)
    out += byte(c.get("samples_per_pixel", 4) - 1)
    for v in c.get("point", (10.0, -20.0, 2000.0)):
        out += real(v)
    return out


THIN = {"type": "thin_lens", "focal_length": 16.0, "f_number": 4.0, "focus_distance": 2.0}
HEX = {"grid": "hexagonal", "pitch": 0.08, "lens": "thin_lens", "focal_lengths": [0.32], "distance": 0.32}
SMALL = {"pixel_size": (0.01, 0.01)}


def with_(base, **kw):
    d = dict(base)
    d.update(kw)
    return d


SEEDS = {
    # the submodels
    "pinhole_none": {"main": {"type": "pinhole", "distance": 20.0}, "sensor": SMALL},
    "thin_none": {"main": THIN, "sensor": SMALL},
    "none_pinhole": {"array": with_(HEX, grid="rectangular", lens="pinhole", focal_lengths=[]), "sensor": SMALL},
    "none_thin": {"array": HEX, "sensor": SMALL},
    "thin_pinhole": {"main": THIN, "array": with_(HEX, lens="pinhole", focal_lengths=[]), "sensor": SMALL},
    "thin_thin_1": {"main": THIN, "array": HEX, "sensor": SMALL},
    "thin_thin_2": {"main": THIN, "array": with_(HEX, distance=0.4), "sensor": SMALL},
    "thin_thin_multifocus": {"main": THIN, "array": with_(HEX, focal_lengths=[0.25, 0.3, 0.35], distance=0.4,
                                                           rotate=(2.0, -1.0, 10.0), translate=(0.01, 0.0, 0.02)),
                             "sensor": SMALL, "samples": {"adaptive": True, "min": 2, "max": 8}},
    "pinhole_thin": {"main": {"type": "pinhole", "distance": 16.0}, "array": with_(HEX, focal_lengths=[0.25]),
                     "sensor": SMALL},
    "overlap": {"main": with_(THIN, f_number=1.4), "array": HEX, "sensor": SMALL},
    # singular-looking, all legal
    "d_eq_f_exact": {"main": with_(THIN, focus_distance=None) | {"distance": 16.5}, "array": HEX, "sensor": SMALL},
    "d_f_plus_1e-12": {"main": THIN, "array": with_(HEX, distance=0.32 * (1 + 1e-12)), "sensor": SMALL},
    "D_eq_F": {"main": {"type": "thin_lens", "focal_length": 16.0, "f_number": 4.0, "distance": 16.0},
               "array": HEX, "sensor": SMALL},
    "focus_1e9": {"main": with_(THIN, focus_distance=1e9), "array": HEX, "sensor": SMALL},
    "F_1e-6": {"main": with_(THIN, focal_length=1e-6), "array": HEX, "sensor": SMALL},
    "F_1e6": {"main": with_(THIN, focal_length=1e6, focus_distance=1e4), "array": HEX, "sensor": SMALL},
    "f_1e-6": {"main": THIN, "array": with_(HEX, focal_lengths=[1e-6]), "sensor": SMALL},
    "f_1e6": {"main": THIN, "array": with_(HEX, focal_lengths=[1e6]), "sensor": SMALL},
    "tilt_89.99": {"main": THIN, "array": with_(HEX, rotate=(89.99, 0.0, 0.0)), "sensor": SMALL},
    # an array tilted almost edge-on over a tiny picture: ~400,000 candidate lenses for the point
    # (a libFuzzer timeout under load before the cheap rejection in forward projection)
    "tilt_89.99_short_focus": {"main": with_(THIN, focal_length=2.0), "array": with_(HEX, rotate=(89.99, 0.0, 0.0)),
                               "sensor": {"pixel_size": (0.01, 0.010019531264911166)}, "image": (16, 2),
                               "pixels": [(0, 0), (8, 1)], "samples_per_pixel": 1, "point": (0.0, 0.0, 2.0)},
    "rotate_1e-9": {"main": THIN, "array": with_(HEX, rotate=(0.0, 0.0, 1e-9)), "sensor": SMALL},
    "pinhole_tilt_89.99": {"main": {"type": "pinhole", "distance": 1.0},
                           "array": with_(HEX, grid="rectangular", focal_lengths=[1e-6], distance=0.35,
                                          rotate=(0.0, 89.9, 0.0)), "sensor": SMALL},
    "offset_corner": {"main": THIN, "array": HEX, "sensor": {"pixel_size": (0.01, 0.01), "offset": (0.16, 0.12)}},
    "mm_per_unit_1e-6": {"mm_per_unit": 1e-6, "main": {"type": "thin_lens", "focal_length": 16.0, "f_number": 4.0,
                                                       "distance": 16.5}, "array": HEX, "sensor": SMALL},
    "mm_per_unit_1e9": {"mm_per_unit": 1e9, "main": THIN, "array": HEX, "sensor": SMALL},
    "one_pixel_pitch": {"main": THIN, "array": with_(HEX, pitch=0.01), "sensor": SMALL},
    "one_lens": {"main": THIN, "array": with_(HEX, grid="rectangular", pitch=1.0), "sensor": SMALL},
    "image_1x1": {"main": THIN, "array": HEX, "sensor": SMALL, "image": (1, 1), "pixels": [(0, 0)]},
    "huge_focus_F_1e300": {"mm_per_unit": 1.0, "main": {"type": "thin_lens", "focal_length": 1e300, "f_number": 4.0,
                                                         "focus_distance": 1.0000000000000002e300},
                           "array": HEX, "sensor": SMALL},
    # refusals
    "nan_focal_length": {"main": with_(THIN, focal_length=NAN), "array": HEX, "sensor": SMALL},
    "inf_pitch": {"main": THIN, "array": with_(HEX, pitch=INF), "sensor": SMALL},
    "neg_pixel": {"main": THIN, "array": HEX, "sensor": {"pixel_size": (0.01, -0.01)}},
    "both_f_number_aperture": {"main": with_(THIN, aperture=4.0), "array": HEX, "sensor": SMALL},
    "neither_focus_nor_distance": {"main": {"type": "thin_lens", "focal_length": 16.0, "f_number": 4.0},
                                   "sensor": SMALL},
    "focus_inside_F": {"main": with_(THIN, focus_distance=0.01), "sensor": SMALL},
    "focal_lengths_rect": {"main": THIN, "array": with_(HEX, grid="rectangular", focal_lengths=[0.3, 0.32, 0.34]),
                           "sensor": SMALL},
    "pinhole_pinhole": {"main": {"type": "pinhole", "distance": 17.0},
                        "array": with_(HEX, lens="pinhole", focal_lengths=[]), "sensor": SMALL},
    "samples_0": {"main": THIN, "sensor": SMALL, "samples": {"samples": 0}},
    "adaptive_min_gt_max": {"main": THIN, "sensor": SMALL, "samples": {"adaptive": True, "min": 16, "max": 4}},
    "confidence_1.5": {"main": THIN, "sensor": SMALL, "samples": {"adaptive": True, "min": 2, "max": 8,
                                                                  "confidence": 1.5}},
    "edge_on": {"main": THIN, "array": with_(HEX, rotate=(90.0, 0.0, 0.0)), "sensor": SMALL},
    "nothing": {"sensor": SMALL},
}


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    corpus = os.path.join(here, "corpus")
    # Rewrites the generated seeds; keeps the reproducers committed as they were found (regression_*).
    os.makedirs(corpus, exist_ok=True)
    for name in os.listdir(corpus):
        if not name.startswith("regression_"):
            os.remove(os.path.join(corpus, name))
    for name, camera in sorted(SEEDS.items()):
        main_lens = camera.get("main")
        if main_lens is not None:
            camera = dict(camera, main={k: v for k, v in main_lens.items() if v is not None})
        with open(os.path.join(corpus, name + ".bin"), "wb") as f:
            f.write(encode(camera))
    print("wrote %d seeds to %s" % (len(SEEDS), corpus))


if __name__ == "__main__":
    main()
