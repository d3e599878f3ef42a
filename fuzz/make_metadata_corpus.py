#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Writes the seed corpus of the metadata-reader fuzzer (fuzz/corpus-metadata/*.json).

Real metadata files, rendered by the povray given (tiny images: every submodel), and copies of
one broken the ways the reader must refuse cleanly: duplicate keys, lone surrogates, bytes that
are not UTF-8, truncations, a NaN, deep nesting, wrong types.

    python3 fuzz/make_metadata_corpus.py --povray build/povray     # rewrites fuzz/corpus-metadata/
"""
import argparse
import os
import shutil
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "corpus-metadata")

THIN = "main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }"
SCENES = {
    "real_thin_hexagonal": THIN + " microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 } samples 1",
    "real_thin_rectangular_posed": THIN + " microlens_array { rectangular pitch 0.15 focal_length 0.5 distance 0.575"
                                   " rotate <1, -2, 7> translate <0.25, -0.1, 0.01> } samples 1 depth_map",
    "real_multifocus": THIN + " microlens_array { hexagonal pitch 0.15 focal_lengths <0.6, 0.7, 0.8> distance 0.6 }"
                       " samples 2, 8",
    "real_camera_array": "microlens_array { rectangular pitch 0.3 pinhole distance 1.5 }",
    "real_thin_none": THIN + " samples 1",
    "real_pinhole_thin": "main_lens { pinhole distance 16 } microlens_array { hexagonal pitch 0.15 focal_length 0.6"
                         " distance 0.6 }",
}


def render(povray, work, name, body):
    scene = ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\ncamera {\n  plenoptic\n  location <0.1, 0.2, -2>\n"
             "  look_at <0, 0, 0>\n  sensor { pixel_size 0.02 }\n  %s\n}\nsphere { 0, 0.3 pigment { rgb 1 } }\n" % body)
    with open(os.path.join(work, name + ".pov"), "w") as f:
        f.write(scene)
    subprocess.run([povray, "+I" + name + ".pov", "+O" + name + ".png", "+W40", "+H30", "-D", "-P", "-V"],
                   cwd=work, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(work, name + ".plenoptic.json"), "rb") as f:
        return f.read()


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--povray", required=True)
    args = ap.parse_args()
    seeds = {}
    with tempfile.TemporaryDirectory() as work:
        for name, body in SCENES.items():
            seeds[name] = render(os.path.abspath(args.povray), work, name, body)
    good = seeds["real_thin_hexagonal"]

    def broken(old, new):
        assert old in good, old
        return good.replace(old, new, 1)

    seeds.update({
        "duplicate_top_level_key": broken(b'"mm_per_unit": 1000,', b'"mm_per_unit": 1000,\n  "mm_per_unit": 500,'),
        "duplicate_nested_key": broken(b'"pitch_mm":', b'"pitch_mm": 0.3,\n    "pitch_mm":'),
        "lone_high_surrogate": broken(b'"depth_map": null', b'"depth_map": "\\ud800.exr"'),
        "lone_low_surrogate": broken(b'"depth_map": null', b'"depth_map": "\\udc00.exr"'),
        "surrogate_pair": broken(b'"depth_map": null', b'"depth_map": "\\ud83d\\ude00 \xc3\xa9.exr"'),
        "latin1_byte": broken(b'"depth_map": null', b'"depth_map": "caf\xe9.exr"'),
        "overlong_utf8": broken(b'"depth_map": null', b'"depth_map": "\xc0\xaf.exr"'),
        "truncated_half": good[:len(good) // 2],
        "truncated_in_string": good[:good.index(b'"hexagonal"') + 4],
        "truncated_in_number": good[:good.index(b'"pitch_mm": 0.15') + 14],
        "nan": broken(b'"mm_per_unit": 1000', b'"mm_per_unit": NaN'),
        "huge_number": broken(b'"mm_per_unit": 1000', b'"mm_per_unit": 1e400'),
        "width_as_float": broken(b'"width": 40', b'"width": 40.0'),
        "null_lattice": broken(b'"microimage_lattice": {', b'"microimage_lattice": null, "x": {'),
        "deep_nesting": b"[" * 3000,
        "empty": b"",
    })
    if os.path.isdir(OUT):
        shutil.rmtree(OUT)
    os.makedirs(OUT)
    for name, data in sorted(seeds.items()):
        with open(os.path.join(OUT, name + ".json"), "wb") as f:
            f.write(data)
    print("wrote %d seeds to %s" % (len(seeds), OUT))


if __name__ == "__main__":
    main()
