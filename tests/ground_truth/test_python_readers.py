# SPDX-License-Identifier: AGPL-3.0-or-later
"""The Python tools read images, read metadata and run POV-Ray one way each (python/plenoptic_lf:
images.py, metadata.py, povray.py), and the tests' helper reads through the same code.

  - Images: every reader (the decoder's raw, values-as-stored and depth-map readers, the row-band
    merge's, the tests' helper's) returns the new pixels of a file written again under the same
    name; the ImageBuf readers returned the first pixels read from that path (OpenImageIO's image
    cache). No ImageBuf is left in python/ or tests/pylib, and ImageInput is opened in images.py
    only.
  - Metadata: plenoptic-decode validates against docs/metadata.schema.json, so a field the schema
    does not have, or NaN in a field the decoder itself does not check, is refused in one line
    (exit 2) where it used to be decoded; read_metadata's typed fields are the file's values;
    the tests' helper reads with the same strict reader (the decoder's messages).
  - POV-Ray runner: a time limit kills the whole process group; Ctrl-C sends SIGINT to it.
Renders one small plenoptic scene (about 2 s).
"""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import plenoptic_testing as pt

SCENE = """camera {
  plenoptic
  location <0, 0, -2>
  look_at <0, 0, 0>
  main_lens { thin_lens focal_length 50 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 }
  sensor { pixel_size 0.01 }
  depth_map on
  white_image on
}
sky_sphere { pigment { rgb <0.6, 0.7, 0.9> } }
sphere { 0, 0.3 pigment { checker rgb 1 rgb <1, 0.2, 0.1> scale 0.1 } finish { emission 1 diffuse 0 } }
"""


@pytest.fixture(scope="module")
def render(args):
    png, meta, depth = pt.render_ground_truth(args.povray, args.work, "readers", SCENE, 96, 72)
    return png, meta, depth


def write_image(path, value, fmt="uint16", channels=3):
    """An 8 x 6 image of one value through OpenImageIO's ImageOutput (not the reader under test)."""
    import OpenImageIO as oiio
    spec = oiio.ImageSpec(8, 6, channels, {"uint16": oiio.UINT16, "float": oiio.FLOAT}[fmt])
    out = oiio.ImageOutput.create(path)
    assert out is not None and out.open(path, spec), oiio.geterror()
    out.write_image(np.full((6, 8, channels), value, np.float32))
    out.close()


def readers():
    import plenoptic_lf as plf
    from plenoptic_lf.dataset import bands
    from plenoptic_lf.images import read_stored
    return {
        "read_raw": (".png", lambda p: plf.read_raw(p, "linear")),
        "read_stored (raw in DN, white images)": (".png", read_stored),
        "read_depth_map": (".exr", plf.read_depth_map),
        "row bands' reader": (".png", lambda p: bands._read(p)[1].astype(np.float64) / 65535.0),
        "tests' helper": (".png", pt.read_pixels),
    }


@pytest.mark.parametrize("name", list(readers()))
def test_a_rewritten_image_is_read_anew(args, name):
    suffix, read = readers()[name]
    stale = []
    for k in range(5):
        path = os.path.join(args.work, "rewritten_%d%s" % (k, suffix))
        write_image(path, 0.25, "float" if suffix == ".exr" else "uint16")
        first = float(np.mean(read(path)))
        write_image(path, 0.75, "float" if suffix == ".exr" else "uint16")
        second = float(np.mean(read(path)))
        assert abs(first - 0.25) < 1e-4, "%s: the first file's pixels %g (want 0.25)" % (name, first)
        if abs(second - 0.75) > 1e-4:
            stale.append(second)
    assert not stale, "%s: %d of 5 files written again under the same name read as before: %s" % (name, len(stale), stale)


def python_sources(args):
    roots = [args.python, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "pylib")]
    for root in roots:
        for folder, _, files in os.walk(root):
            for n in files:
                if n.endswith(".py") and "__pycache__" not in folder:
                    path = os.path.join(folder, n)
                    with open(path, encoding="utf-8") as f:
                        yield os.path.relpath(path, os.path.dirname(root)), f.read()


def test_one_image_reader_in_the_sources(args):
    image_buf = sorted(p for p, text in python_sources(args) if "ImageBuf(" in text)
    image_input = sorted(p for p, text in python_sources(args) if "ImageInput.open(" in text)
    assert not image_buf, "OpenImageIO's ImageBuf (whose cache returns stale pixels) is used in %s" % image_buf
    assert image_input == [os.path.join("python", "plenoptic_lf", "images.py")], (
        "ImageInput is opened in images.py only, found in %s" % image_input)


def decode(args, png, meta, out):
    return subprocess.run(pt.decoder(args.tools) + ["-q", png, meta, "-o", out], capture_output=True, text=True)


@pytest.mark.parametrize("label, edit, words", [
    ("a field the schema does not have", lambda d: d.update(lens_maker="acme"),
     ["docs/metadata.schema.json", "lens_maker"]),
    ("NaN in a field the decoder does not check",
     lambda d: d["microimage_lattice"].update(microimage_diameter_px=float("nan")),
     ["microimage_lattice.microimage_diameter_px", "non-finite"]),
])
def test_decoder_validates_against_the_schema(args, render, label, edit, words):
    png, meta, _ = render
    doc = pt.load_metadata(meta)
    ok = decode(args, png, meta, os.path.join(args.work, "schema_ok.lightfield"))
    assert ok.returncode == 0, "the unbroken metadata decodes (control): %s" % ok.stderr[-300:]
    edit(doc)
    broken = os.path.join(args.work, "schema_%s.plenoptic.json" % label.split()[0].lower())
    with open(broken, "w") as f:
        json.dump(doc, f, indent=1)  # NaN written as Python's json writes it
    out = os.path.join(args.work, "schema_broken.lightfield")
    run = decode(args, png, broken, out)
    lines = [l for l in run.stderr.splitlines() if l.strip()]
    assert (run.returncode == 2 and len(lines) == 1 and lines[0].startswith("plenoptic-decode: error: " + broken)
            and all(w in lines[0] for w in words) and not os.path.exists(os.path.join(out, "contact_sheet.png"))), (
        "decode, %s: exit %d (want 2), stderr %r (want one line naming %s)" % (label, run.returncode, run.stderr, words))


def test_typed_metadata_holds_the_files_values(args, render):
    from plenoptic_lf.metadata import load_metadata, read_metadata
    png, meta, _ = render
    doc = pt.load_metadata(meta)
    typed = read_metadata(meta)
    assert typed.raw == doc and load_metadata(meta, (96, 72)).raw == doc
    frame = doc["camera_frame"]
    assert typed.camera_frame.location == tuple(frame["location"]) and typed.camera_frame.direction == tuple(
        frame["direction"]) and typed.camera_frame.up == tuple(frame["up"]) and typed.camera_frame.right == tuple(frame["right"])
    lens, array = doc["main_lens"], doc["microlens_array"]
    assert (typed.main_lens.type, typed.main_lens.focal_length_mm, typed.main_lens.f_number, typed.main_lens.aperture_mm,
            typed.main_lens.distorted) == ("thin_lens", lens["focal_length_mm"], lens["f_number"], lens["aperture_mm"],
                                           lens.get("distortion") is not None)
    assert (typed.array.grid, typed.array.lens, list(typed.array.focal_lengths_mm), typed.array.pitch_mm,
            typed.array.distance_mm, list(typed.array.rotate_deg), list(typed.array.translate_mm)) == (
        array["grid"], array["lens"], array["focal_lengths_mm"], array["pitch_mm"], array["distance_mm"],
        array["rotate_deg"], array["translate_mm"])
    assert [(w.file, w.values, w.scale) for w in typed.white_images] == [
        (w["file"], w["values"], w.get("scale", 1)) for w in doc["white_images"]] and typed.white_images
    assert (typed.width, typed.height, typed.mm_per_unit, list(typed.pixel_size_mm)) == (
        doc["image"]["width"], doc["image"]["height"], doc["mm_per_unit"], doc["sensor"]["pixel_size_mm"])
    assert typed.principal_point_px == tuple(doc["principal_point_px"]) and typed.diffraction == (doc["diffraction"] is not None)
    assert typed.sidecar_path("depth_map") == os.path.join(os.path.dirname(os.path.abspath(meta)), doc["depth_map"])


def test_helper_reads_with_the_tools_strict_reader(args, render):
    _, meta, _ = render
    text = open(meta, encoding="utf-8").read().replace('"version":', '"version": 1, "version":', 1)
    with pytest.raises(pt.MetadataError, match="duplicate key 'version' in one object"):
        pt.parse_json_strict(text, "doubled")
    with pytest.raises(pt.MetadataError, match="non-finite"):
        pt.parse_json_strict(text.replace('"version": 1, "version":', '"nan": NaN, "version":'), "nan")


RUNNER = """import signal, sys
# Ctrl-C raises KeyboardInterrupt here even when this test runs with SIGINT ignored (a background
# job); the command then starts with SIGINT at its default, as from a terminal.
signal.signal(signal.SIGINT, signal.default_int_handler)
sys.path.insert(0, %r)
from plenoptic_lf.povray import run_povray
try:
    run_povray(["sh", "-c", sys.argv[1]], timeout=float(sys.argv[2]))
    print("finished")
except KeyboardInterrupt:
    print("interrupted")
"""


def test_runner_kills_the_process_group_at_the_time_limit(args):
    """The command's own child (a background sleep) is killed with it."""
    from plenoptic_lf.povray import run_povray
    pid_file = os.path.join(args.work, "runner_child.pid")
    run = run_povray(["sh", "-c", "sleep 60 & echo $! > %s; wait" % pid_file], timeout=1.0)
    assert run.timed_out and not run.ok and run.seconds < 30, (run.timed_out, run.seconds)
    child = int(open(pid_file).read())
    time.sleep(0.2)
    alive = os.path.exists("/proc/%d" % child) and "zombie" not in open("/proc/%d/status" % child).read().lower() \
        if os.path.exists("/proc/%d" % child) else False
    assert not alive, "the command's child %d outlived the time limit" % child


def test_runner_passes_ctrl_c_on(args):
    """SIGINT to the tool: the command gets SIGINT (its trap writes a file), the tool's
    KeyboardInterrupt goes on."""
    marker = os.path.join(args.work, "runner_sigint")
    started = marker + ".started"
    for path in (marker, started):
        if os.path.exists(path):
            os.remove(path)
    script = "trap 'echo got > %s; exit 3' INT; : > %s; sleep 60 & wait" % (marker, started)
    driver = subprocess.Popen([sys.executable, "-c", RUNNER % args.python, script, "120"], stdout=subprocess.PIPE,
                              text=True)
    deadline = time.monotonic() + 60
    while not os.path.exists(started) and time.monotonic() < deadline and driver.poll() is None:
        time.sleep(0.05)
    assert os.path.exists(started), "the command did not start"
    driver.send_signal(signal.SIGINT)
    out, _ = driver.communicate(timeout=60)
    assert out.strip() == "interrupted" and os.path.exists(marker), (out, os.path.exists(marker))
