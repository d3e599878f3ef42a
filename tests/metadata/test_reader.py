# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-project reads metadata as strict JSON in UTF-8, as docs/metadata.md promises.

Renders one tiny plenoptic scene, checks that plenoptic-project projects with its metadata, then
feeds it copies broken in ways a JSON library must catch and a hand-written parser did not:
  - a lone UTF-16 surrogate escape (\\ud800, \\udc00, a high surrogate followed by a non-surrogate);
  - bytes that are not UTF-8 (Latin-1, an overlong encoding, an encoded surrogate, a cut sequence);
  - a key twice in one object (the old reader took the first, Python's json the last: refused);
  - the file cut short.
Each must end plenoptic-project with exit status 2 and one line naming the file and the cause.
A surrogate pair and raw UTF-8 in a string must still be accepted. Finally the rendered file's
numbers are in their shortest round-trip form (a pitch of 0.15 is written 0.15).
"""

import argparse
import os
import subprocess
import sys

SCENE = """#version 3.7;
global_settings { assumed_gamma 1.0 }
camera {
  plenoptic
  location <0, 0, -2>
  look_at <0, 0, 0>
  main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }
  sensor { pixel_size 0.02 }
  samples 1
}
sphere { 0, 0.3 pigment { rgb 1 } finish { emission 1 diffuse 0 } }
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--povray", required=True)
    ap.add_argument("--project", required=True, help="the plenoptic-project binary")
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    failures = []

    def check(ok, message):
        print(("ok    " if ok else "FAIL  ") + message)
        if not ok:
            failures.append(message)

    with open(os.path.join(args.work, "reader.pov"), "w") as f:
        f.write(SCENE)
    meta = os.path.join(args.work, "reader.plenoptic.json")
    if os.path.exists(meta):
        os.remove(meta)
    run = subprocess.run([args.povray, "+Ireader.pov", "+Oreader.png", "+W48", "+H36", "-D", "-P", "-V"],
                         cwd=args.work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    if run.returncode != 0 or not os.path.exists(meta):
        print(run.stdout.decode(errors="replace")[-2000:])
        print("FAIL  render (exit %d)" % run.returncode)
        return 1
    with open(meta, "rb") as f:
        good = f.read()

    def project(path):
        r = subprocess.run([args.project, path, "0", "0", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        return r.returncode, r.stdout.decode(errors="replace"), r.stderr.decode(errors="replace")

    code, out, err = project(meta)
    check(code == 0 and out.strip(), "the rendered metadata projects (exit %d, %r)" % (code, err.strip()))

    def variant(name, data):
        path = os.path.join(args.work, "reader_" + name + ".plenoptic.json")
        with open(path, "wb") as f:
            f.write(data)
        return path

    def replaced(old, new):
        assert old in good, old
        return good.replace(old, new, 1)

    null_depth = b'"depth_map": null'
    cases = [
        ("lone high surrogate", replaced(null_depth, b'"depth_map": "\\ud800.exr"'), ["surrogate"]),
        ("lone low surrogate", replaced(null_depth, b'"depth_map": "\\udc00.exr"'), ["surrogate"]),
        ("high surrogate then a letter", replaced(null_depth, b'"depth_map": "\\ud83d\\u0041.exr"'), ["surrogate"]),
        ("Latin-1 byte", replaced(null_depth, b'"depth_map": "caf\xe9.exr"'), ["UTF-8"]),
        ("overlong encoding", replaced(null_depth, b'"depth_map": "\xc0\xaf.exr"'), ["UTF-8"]),
        ("encoded surrogate", replaced(null_depth, b'"depth_map": "\xed\xa0\x80.exr"'), ["UTF-8"]),
        ("cut sequence", replaced(null_depth, b'"depth_map": "\xe2\x82"'), ["UTF-8"]),
        ("duplicate top-level key", replaced(b'"mm_per_unit": 1000,', b'"mm_per_unit": 1000,\n  "mm_per_unit": 500,'),
         ["duplicate key 'mm_per_unit'"]),
        ("duplicate key, same value", replaced(b'"version": 1,', b'"version": 1,\n  "version": 1,'),
         ["duplicate key 'version'"]),
        ("duplicate nested key", replaced(b'"pitch_mm":', b'"pitch_mm": 0.3,\n    "pitch_mm":'),
         ["duplicate key 'pitch_mm'", "microlens_array"]),
        ("truncated", good[:len(good) // 2], ["not valid JSON", "line"]),
        ("truncated inside a string", good[:good.index(b'"hexagonal"') + 4], ["not valid JSON"]),
        ("empty file", b"", ["not valid JSON"]),
    ]
    for label, data, words in cases:
        path = variant(label.replace(" ", "_").replace(",", ""), data)
        code, out, err = project(path)
        lines = [l for l in err.splitlines() if l.strip()]
        ok = (code == 2 and out == "" and len(lines) == 1 and lines[0].startswith("plenoptic-project: " + path + ": ")
              and all(w in lines[0] for w in words) and lines[0].isprintable() and lines[0].isascii())
        check(ok, "%s: refused, exit %d (want 2), stderr %r (want one line naming the file and %s)"
              % (label, code, err.strip()[-300:], words))

    # Accepted: a surrogate pair, raw UTF-8, and non-ASCII in a string.
    path = variant("utf8", replaced(null_depth, '"depth_map": "sc\\u00e9ne \\ud83d\\ude00 é.exr"'.encode("utf-8")))
    code, out, err = project(path)
    check(code == 0 and out.strip(), "a surrogate pair and UTF-8 in a string are accepted (exit %d, %r)"
          % (code, err.strip()))

    # The writer: shortest round-trip numbers.
    check(b'"pitch_mm": 0.15,' in good and b"0.14999999999999999" not in good,
          "the rendered file writes the pitch 0.15 as 0.15 (%r)"
          % [l.strip() for l in good.splitlines() if b"pitch_mm" in l])
    check(b'"focal_lengths_mm": [0.6]' in good and b'"distance_mm": 0.6,' in good,
          "and the microlens focal length and distance 0.6 as 0.6")

    if failures:
        print("metadata_reader: %d check(s) failed" % len(failures))
        return 1
    print("metadata_reader: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
