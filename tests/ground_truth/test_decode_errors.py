# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode and plenoptic-project refuse missing or garbled metadata cleanly.

A tiny plenoptic render and a tiny thin-lens-only render (metadata without an array) give real
files; the test then breaks the metadata in the ways a user might (missing, truncated, not
JSON, wrong format, a missing or malformed field, a non-finite number, the wrong image size) and
checks that each tool exits with status 2, prints exactly one line naming the problem (and the
field, where there is one) and no Python traceback, and writes no contact sheet. The unbroken
files must decode and project (exit 0) so that the refusals are not the tools failing anyway.
"""

import json
import os
import shutil
import subprocess
import types

import pytest

import plenoptic_testing as pt

SCENE_ARRAY = """camera {
  plenoptic
  location <0, 0, -2>
  look_at <0, 0, 0>
  main_lens { thin_lens focal_length 50 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 }
  sensor { pixel_size 0.01 }
}
sky_sphere { pigment { rgb <0.6, 0.7, 0.9> } }
sphere { 0, 0.3 pigment { checker rgb 1 rgb <1, 0.2, 0.1> scale 0.1 } finish { emission 1 diffuse 0 } }
"""

SCENE_NO_ARRAY = """camera {
  plenoptic
  location <0, 0, -2>
  look_at <0, 0, 0>
  main_lens { thin_lens focal_length 50 f_number 4 focus_distance 2 }
  sensor { pixel_size 0.02 }
}
sphere { 0, 0.3 pigment { rgb 1 } finish { emission 1 diffuse 0 } }
"""


def run(cmd):
    return subprocess.run(cmd, capture_output=True, text=True, errors="replace")


def drop(path):
    def edit(data):
        node = data
        parts = path.split(".")
        for p in parts[:-1]:
            node = node[p]
        del node[parts[-1]]
    return edit


def setter(path, value):
    def edit(data):
        node = data
        parts = path.split(".")
        for p in parts[:-1]:
            node = node[p]
        node[parts[-1]] = value
    return edit


@pytest.fixture(scope="module")
def renders(args):
    """The two real renders, their metadata, and broken(name, edit=None, text=None): a copy of the
    plenoptic render's metadata broken by edit(dict) or replaced by text."""
    png, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "decode_ok", SCENE_ARRAY, 96, 72)
    png_plain, meta_plain, _ = pt.render_ground_truth(args.povray, args.work, "decode_no_array", SCENE_NO_ARRAY, 64, 48)
    good = pt.read_json(meta_path)
    bad_dir = os.path.join(args.work, "decode_bad")
    shutil.rmtree(bad_dir, ignore_errors=True)
    os.makedirs(bad_dir)
    text = open(meta_path).read()

    def broken(name, edit=None, text=None):
        path = os.path.join(bad_dir, name + ".plenoptic.json")
        if text is None:
            data = json.loads(json.dumps(good))
            edit(data)
            text = json.dumps(data, indent=1)
        with open(path, "wb") as f:
            f.write(text if isinstance(text, bytes) else text.encode("utf-8"))
        return path

    return types.SimpleNamespace(png=png, meta_path=meta_path, png_plain=png_plain, meta_plain=meta_plain,
                                 good=good, text=text, bad_dir=bad_dir, broken=broken,
                                 decode=pt.decoder(args.tools) + ["-q"])


def test_unbroken_files_decode_and_project(args, renders):
    """Positive controls."""
    out = os.path.join(args.work, "decode_ok.lightfield")
    result = run(renders.decode + [renders.png, "-o", out])
    assert (result.returncode == 0 and os.path.exists(os.path.join(out, "contact_sheet.png"))), (
        "the unbroken render decodes (exit %d, stderr %r)" % (result.returncode, result.stderr.strip()[-300:]))
    result = run([args.project, renders.meta_path, "0", "0", "0"])
    assert (result.returncode == 0 and len(result.stdout.split()) >= 5), (
        "plenoptic-project projects the sphere's centre with the unbroken metadata (exit %d, output %r)"
        % (result.returncode, result.stdout.strip()))


# label, the broken file (a function of the renders fixture), words the one error line must hold,
# and for plenoptic-project: True it must refuse it too, naming the same field; False a field it
# does not need; "projects" a file it must accept.
CASES = [
    ("missing file", lambda r: os.path.join(r.bad_dir, "absent.plenoptic.json"), ["cannot read"], True),
    ("truncated", lambda r: r.broken("truncated", text=r.text[:len(r.text) // 2]), ["not valid JSON"], True),
    ("not JSON at all", lambda r: r.broken("binary", text=b"\x89PNG\r\n\x1a\n\x00\x00garbage"), ["not valid JSON"], True),
    # Both readers are strict where Python's json is lax (docs/metadata.md, "Reading it").
    ("duplicate key", lambda r: r.broken("dupkey", text=r.text.replace('"mm_per_unit":', '"mm_per_unit": 10, "mm_per_unit":', 1)),
     ["duplicate key 'mm_per_unit'"], True),
    ("lone surrogate", lambda r: r.broken("surrogate", text=r.text.replace('"format":', '"depth": "\\ud800", "format":', 1)),
     ["surrogate"], True),
    ("Latin-1 byte", lambda r: r.broken("latin1", text=r.text.encode("utf-8").replace(b'"format":', b'"depth": "caf\xe9", "format":', 1)),
     ["UTF-8"], True),
    ("a JSON array", lambda r: r.broken("array", text="[1, 2, 3]"), ["object"], True),
    ("wrong format", lambda r: r.broken("format", setter("format", "something-else")), ["format"], True),
    ("wrong version", lambda r: r.broken("version", setter("version", 7)), ["version"], True),
    ("no lattice basis", lambda r: r.broken("nobasis", drop("microimage_lattice.basis_px")),
     ["microimage_lattice.basis_px"], False),
    ("basis not numbers", lambda r: r.broken("basisstr", setter("microimage_lattice.basis_px", "wide")),
     ["microimage_lattice.basis_px"], False),
    ("NaN origin", lambda r: r.broken("nan", setter("microimage_lattice.origin_px", [float("nan"), 1.0])),
     ["microimage_lattice.origin_px"], False),
    ("image size", lambda r: r.broken("size", setter("image.width", r.good["image"]["width"] + 8)), ["image.width"], True),
    ("pixel size", lambda r: r.broken("pixel", setter("sensor.pixel_size_mm", [0, 0.01])), ["sensor.pixel_size_mm"], True),
    ("focal length null", lambda r: r.broken("focal", setter("main_lens.focal_length_mm", None)),
     ["main_lens.focal_length_mm"], True),
    ("array distance negative", lambda r: r.broken("distance", setter("microlens_array.distance_mm", -0.4)),
     ["microlens_array.distance_mm"], True),
    ("no array", lambda r: r.meta_plain, ["microlens_array"], "projects"),
]


@pytest.mark.parametrize("label, make, words, project_too", CASES, ids=[c[0] for c in CASES])
def test_broken_metadata_refused(args, renders, label, make, words, project_too):
    path = make(renders)
    image = renders.png_plain if path == renders.meta_plain else renders.png
    target = os.path.join(renders.bad_dir, "out_" + label.replace(" ", "_"))
    result = run(renders.decode + [image, path, "-o", target])
    lines = [l for l in result.stderr.splitlines() if l.strip()]
    ok = (result.returncode == 2 and len(lines) == 1 and lines[0].startswith("plenoptic-decode: error:")
          and all(w in lines[0] for w in words) and "Traceback" not in result.stderr
          and not os.path.exists(os.path.join(target, "contact_sheet.png")))
    assert ok, ("decode, %s: exit %d (want 2), stderr %r (want one line mentioning %s)"
                % (label, result.returncode, result.stderr.strip()[-400:], words))
    # plenoptic-project reads the same file.
    if project_too is False:
        return
    result = run([args.project, path, "0", "0", "0"])
    lines = [l for l in result.stderr.splitlines() if l.strip()]
    if project_too == "projects":
        assert (result.returncode == 0), ("project, %s: a camera without an array still projects (exit %d, %r)"
                                          % (label, result.returncode, result.stderr.strip()))
        return
    ok = (result.returncode == 2 and len(lines) == 1 and lines[0].startswith("plenoptic-project: " + path)
          and all(w in lines[0] for w in words if w not in ("cannot read", "object")))
    assert ok, "project, %s: exit %d (want 2), stderr %r" % (label, result.returncode, result.stderr.strip())


# plenoptic-project: the field it names when a camera value is wrong.
PROJECT_CASES = [
    ("focal length null", lambda good: setter("main_lens.focal_length_mm", None), "main_lens.focal_length_mm"),
    ("unknown grid", lambda good: setter("microlens_array.grid", "triangular"), "microlens_array.grid"),
    ("edited sensor plane", lambda good: setter("sensor.plane_z_mm", good["sensor"]["plane_z_mm"] - 1),
     "sensor.plane_z_mm"),
]


@pytest.mark.parametrize("label, edit, word", PROJECT_CASES, ids=[c[0] for c in PROJECT_CASES])
def test_project_names_the_field(args, renders, label, edit, word):
    path = renders.broken("project_" + label.replace(" ", "_"), edit(renders.good))
    result = run([args.project, path, "0", "0", "0"])
    assert (result.returncode == 2 and word in result.stderr and len(result.stderr.strip().splitlines()) == 1), (
        "project, %s: exit %d, stderr %r (want 2, one line naming %s)"
        % (label, result.returncode, result.stderr.strip(), word))


# plenoptic-project: bad coordinates.
COORDINATES = [("two coordinates", ["0", "0"]), ("not a number", ["0", "zero", "1"]), ("infinite", ["0", "inf", "1"])]


@pytest.mark.parametrize("label, coords", COORDINATES, ids=[c[0] for c in COORDINATES])
def test_project_refuses_bad_coordinates(args, renders, label, coords):
    result = run([args.project, renders.meta_path] + coords)
    assert (result.returncode == 2 and result.stdout == "" and result.stderr.strip()), (
        "project, %s: exit %d (want 2), stderr %r" % (label, result.returncode, result.stderr.strip()))
