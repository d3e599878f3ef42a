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

import os
import subprocess

import pytest

import plenoptic_testing as pt

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


NULL_DEPTH = b'"depth_map": null'

# label -> (old, new) replaced once in the rendered file, or a function of it; words the one line
# of stderr must hold.
CASES = [
    ("lone high surrogate", (NULL_DEPTH, b'"depth_map": "\\ud800.exr"'), ["surrogate"]),
    ("lone low surrogate", (NULL_DEPTH, b'"depth_map": "\\udc00.exr"'), ["surrogate"]),
    ("high surrogate then a letter", (NULL_DEPTH, b'"depth_map": "\\ud83d\\u0041.exr"'), ["surrogate"]),
    ("Latin-1 byte", (NULL_DEPTH, b'"depth_map": "caf\xe9.exr"'), ["UTF-8"]),
    ("overlong encoding", (NULL_DEPTH, b'"depth_map": "\xc0\xaf.exr"'), ["UTF-8"]),
    ("encoded surrogate", (NULL_DEPTH, b'"depth_map": "\xed\xa0\x80.exr"'), ["UTF-8"]),
    ("cut sequence", (NULL_DEPTH, b'"depth_map": "\xe2\x82"'), ["UTF-8"]),
    ("duplicate top-level key", (b'"mm_per_unit": 1000,', b'"mm_per_unit": 1000,\n  "mm_per_unit": 500,'),
     ["duplicate key 'mm_per_unit'"]),
    ("duplicate key, same value", (b'"version": 1,', b'"version": 1,\n  "version": 1,'),
     ["duplicate key 'version'"]),
    ("duplicate nested key", (b'"pitch_mm":', b'"pitch_mm": 0.3,\n    "pitch_mm":'),
     ["duplicate key 'pitch_mm'", "microlens_array"]),
    ("truncated", lambda good: good[:len(good) // 2], ["not valid JSON", "line"]),
    ("truncated inside a string", lambda good: good[:good.index(b'"hexagonal"') + 4], ["not valid JSON"]),
    ("empty file", lambda good: b"", ["not valid JSON"]),
]


@pytest.fixture(scope="module")
def good(args):
    """The bytes of the rendered metadata."""
    pt.render(args.povray, args.work, "reader", SCENE, 48, 36, options=("-D", "-P", "-V"), relative=True)
    meta = os.path.join(args.work, "reader.plenoptic.json")
    assert os.path.exists(meta), "the render wrote no %s" % meta
    with open(meta, "rb") as f:
        return f.read()


def project(args, path):
    r = subprocess.run([args.project, path, "0", "0", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    return r.returncode, r.stdout.decode(errors="replace"), r.stderr.decode(errors="replace")


def variant(args, name, data):
    path = os.path.join(args.work, "reader_" + name + ".plenoptic.json")
    with open(path, "wb") as f:
        f.write(data)
    return path


def replaced(good, old, new):
    assert old in good, old
    return good.replace(old, new, 1)


def test_rendered_metadata_projects(args, good):
    code, out, err = project(args, os.path.join(args.work, "reader.plenoptic.json"))
    assert code == 0 and out.strip(), "the rendered metadata projects (exit %d, %r)" % (code, err.strip())


@pytest.mark.parametrize("label, change, words", CASES, ids=[c[0] for c in CASES])
def test_broken_metadata_refused(args, good, label, change, words):
    data = change(good) if callable(change) else replaced(good, *change)
    path = variant(args, label.replace(" ", "_").replace(",", ""), data)
    code, out, err = project(args, path)
    lines = [l for l in err.splitlines() if l.strip()]
    ok = (code == 2 and out == "" and len(lines) == 1 and lines[0].startswith("plenoptic-project: " + path + ": ")
          and all(w in lines[0] for w in words) and lines[0].isprintable() and lines[0].isascii())
    assert ok, ("%s: refused, exit %d (want 2), stderr %r (want one line naming the file and %s)"
                % (label, code, err.strip()[-300:], words))


def test_surrogate_pair_and_utf8_accepted(args, good):
    """Accepted: a surrogate pair, raw UTF-8, and non-ASCII in a string."""
    path = variant(args, "utf8", replaced(good, NULL_DEPTH,
                                          '"depth_map": "sc\\u00e9ne \\ud83d\\ude00 é.exr"'.encode("utf-8")))
    code, out, err = project(args, path)
    assert code == 0 and out.strip(), ("a surrogate pair and UTF-8 in a string are accepted (exit %d, %r)"
                                       % (code, err.strip()))


def test_writer_shortest_numbers(good):
    """The writer: shortest round-trip numbers."""
    assert b'"pitch_mm": 0.15,' in good and b"0.14999999999999999" not in good, (
        "the rendered file writes the pitch 0.15 as 0.15 (%r)" % [l.strip() for l in good.splitlines() if b"pitch_mm" in l])
    assert b'"focal_lengths_mm": [0.6]' in good and b'"distance_mm": 0.6,' in good, (
        "and the microlens focal length and distance 0.6 as 0.6")
