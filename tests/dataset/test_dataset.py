# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-dataset on this machine (docs/datasets.md): the spec's items, the manifest against
checksums computed here, the declared values reaching the camera (its metadata) exactly, resuming after
damage and after Ctrl-C, a failing item among good ones, row bands merged into the picture one
render gives (pixel for pixel), and bands refused under diffraction.

The scene: a plenoptic 1.0 camera whose focus distance is swept and a sphere whose position is
drawn; items are small (96 x 72) so that the whole family takes a minute."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np

import plenoptic_testing as pt
from plenoptic_testing.datasets import check_manifest, dataset, manifest, pixels, sha256, write_spec

def test_items_of_the_spec(args):
    spec = write_spec(os.path.join(args.work, "spec"), "two_by_two", focus="[1.0, 1.5, 2.0]")
    run = dataset(args, "items", spec)
    assert run.returncode == 0, run.stderr
    items = [json.loads(line.split(" ", 1)[1]) for line in run.stdout.splitlines()]
    assert len(items) == 3 * 2, "3 swept values x 2 draws: %d items" % len(items)
    assert [i["Focus"] for i in items] == [1.0, 1.0, 1.5, 1.5, 2.0, 2.0], "sweep order, draws fastest"
    draws = [i["Sphere_X"] for i in items]
    assert all(-0.01 <= x <= 0.01 for x in draws), "uniform draws within [-0.01, 0.01]: %s" % draws
    assert draws[0] == draws[2] == draws[4] and draws[1] == draws[3] == draws[5] and draws[0] != draws[1], (
        "draw k is the same for every swept value, and draws differ: %s" % draws)
    assert [i["Dataset_Samples"] for i in items] == [4] * 6 and [i["Dataset_Item"] for i in items] == list(range(6))
    again = dataset(args, "items", spec)
    assert again.stdout == run.stdout, "the same spec gives the same items (seeded)"
    # Refusals: the file, the key and what is allowed; nothing else.
    for text, key, words in (
            ("[sweep]\nFocus = [1.0, \"x\"]", "sweep.Focus", "finite numbers"),
            ("[random]\ncount = 2\nR = { gamma = [1, 2] }", "random.R", "uniform = [low, high]"),
            ("[random]\ncount = 0", "random.count", "whole number"),
            ("[options]\nsamples = 2.5", "options.samples", "whole number"),
            ("[sweep]\nDataset_Item = [1]", "sweep.Dataset_Item", "Dataset_"),
            ("wdith = 3", "wdith", "unknown key"),
            ('povray_options = ["+FT"]', "povray_options", "(+FE)"),
            ('povray_options = ["+O/tmp/x.png"]', "povray_options", "set by plenoptic-dataset"),
            ('povray_options = ["Width=64"]', "povray_options", "set by plenoptic-dataset"),
            ('povray_options = ["Output_File_Type=J"]', "povray_options", "set by plenoptic-dataset"),
            ('povray_options = ["+HIx.inc"]', "povray_options", "set by plenoptic-dataset"),
            ("[sweep\nFocus = [1]", None, "not valid TOML")):
        path = os.path.join(args.work, "spec", "bad.toml")
        pt.write_text(path, 'scene = "scene.pov"\nwidth = 96\nheight = 72\n' + text + "\n")
        run = dataset(args, "items", path)
        line = run.stderr.strip()
        assert run.returncode == 2 and "bad.toml" in line and (key is None or key in line) and words in line \
            and "\n" not in line and "Traceback" not in line, "%r: exit 2, one line naming %s (%s)" % (text, key, line)


def test_local_run_resume_and_failures(args):
    work = os.path.join(args.work, "local")
    shutil.rmtree(work, ignore_errors=True)
    # 12 digits: a Declare= option would reach the scene as a 32-bit float (1.234568).
    spec = write_spec(work, "sweep", focus="[1.0, 1.23456789012]")
    out = os.path.join(work, "out")
    run = dataset(args, "run", spec, "--out", out)
    assert run.returncode == 0, "a run exits 0 (stderr: %s)" % run.stderr[-2000:]
    assert "4/4 items" in run.stderr and "items/min" in run.stderr and "ETA" in run.stderr, "progress: " + run.stderr
    records = check_manifest(out, 4)
    for record in records.values():
        meta = pt.read_json(os.path.join(out, "items", record["id"], record["id"] + ".plenoptic.json"))
        assert meta["main_lens"]["focus_distance"] == record["parameters"]["Focus"], (
            "the item's Focus reached the camera exactly: %r vs %r" % (meta["main_lens"]["focus_distance"],
                                                                       record["parameters"]))
        assert meta["depth_map"] == record["id"] + ".depth.exr", "options.depth_map reached the camera"
        assert meta["samples"]["max"] == 4, "options.samples reached the camera"

    # Damage: one item's image truncated, another's folder gone. Only those two are rendered again.
    ids = sorted(records)
    image = os.path.join(out, "items", ids[1], records[ids[1]]["image"])
    before = pixels(image)
    with open(image, "r+b") as f:
        f.truncate(100)
    shutil.rmtree(os.path.join(out, "items", ids[2]))
    kept = {i: os.path.getmtime(os.path.join(out, "items", i, "item.json")) for i in (ids[0], ids[3])}
    run = dataset(args, "run", spec, "--out", out)
    assert run.returncode == 0 and "2 of 4 items already finished" in run.stderr, run.stderr
    again = check_manifest(out, 4)
    assert all(os.path.getmtime(os.path.join(out, "items", i, "item.json")) == t for i, t in kept.items()), (
        "finished, verified items are not rendered again")
    assert np.array_equal(pixels(image), before), "the re-rendered item is the same picture (pixels; the PNG's time stamps differ)"

    # A failing item among good ones: reported with its log, the others finished, exit 1.
    bad = write_spec(work, "bad", focus="[1.0, 0.01]")
    bad_out = os.path.join(work, "bad_out")
    run = dataset(args, "run", bad, "--out", bad_out)
    logs = sorted(os.listdir(os.path.join(bad_out, "failed")))
    assert run.returncode == 1 and len(logs) == 2 and "focus_distance" in run.stderr and "log:" in run.stderr, (
        "exit 1, the two items at focus 0.01 reported with POV-Ray's message and their logs (%s)" % run.stderr[-1500:])
    with open(os.path.join(bad_out, "failed", logs[0])) as f:
        assert "focus_distance 0.01" in f.read(), "the kept log holds the parser's message"
    check_manifest(bad_out, 2)
    assert not [n for n in os.listdir(os.path.join(bad_out, "items")) if n.startswith(".")], "no partial folder left"


def test_interrupted_run_resumes(args):
    work = os.path.join(args.work, "interrupt")
    shutil.rmtree(work, ignore_errors=True)
    spec = write_spec(work, "slow", extra="", focus="[1.0, 1.5]")
    with open(spec) as f:
        text = f.read().replace("samples = 4", "samples = 600")
    pt.write_text(spec, text)
    out = os.path.join(work, "out")
    env = dict(os.environ, PYTHONPATH=args.python, PLENOPTIC_POVRAY=args.povray)
    process = subprocess.Popen([sys.executable, "-m", "plenoptic_lf.dataset", "run", spec, "--out", out, "-q"],
                               stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (os.path.isdir(os.path.join(out, "items"))
                                               and any(n.startswith(".partial") for n in os.listdir(os.path.join(out, "items")))):
        time.sleep(0.2)
    time.sleep(1.0)
    start = time.monotonic()
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    stopped = time.monotonic() - start
    assert process.returncode == 130 and "resume" in err, "Ctrl-C: exit 130 and how to resume (%s)" % err
    assert stopped < 5, "it stops promptly (%.1f s)" % stopped
    assert not [n for n in os.listdir(os.path.join(out, "items")) if n.startswith(".")], "no partial folder left"
    leftover = subprocess.run(["pgrep", "-f", os.path.join(work, "scene.pov")], capture_output=True, text=True)
    assert not leftover.stdout.strip(), "no POV-Ray of the data set keeps running: %s" % leftover.stdout
    finished = {r["id"]: os.path.getmtime(os.path.join(out, "items", r["id"], "item.json")) for r in manifest(out)}
    assert len(finished) < 4, "interrupted before the end (%d finished)" % len(finished)
    run = dataset(args, "run", spec, "--out", out)
    assert run.returncode == 0, run.stderr
    check_manifest(out, 4)
    assert all(os.path.getmtime(os.path.join(out, "items", i, "item.json")) == t for i, t in finished.items()), (
        "the items finished before the interruption are kept")


def test_bands_merge_to_one_render(args):
    work = os.path.join(args.work, "bands")
    shutil.rmtree(work, ignore_errors=True)
    spec = write_spec(work, "bands")
    whole, banded = os.path.join(work, "whole"), os.path.join(work, "banded")
    assert dataset(args, "run", spec, "--out", whole, "-q").returncode == 0
    run = dataset(args, "run", spec, "--out", banded, "--bands", "3", "-q")
    assert run.returncode == 0, run.stderr
    a, b = check_manifest(whole, 4), check_manifest(banded, 4)
    assert sorted(a) == sorted(b), "the same items"
    for item_id, record in b.items():
        assert [band["rows"] for band in record["bands"]] == [[0, 23], [24, 47], [48, 71]], record["bands"]
        assert sorted(record["files"]) == sorted(a[item_id]["files"]), "the same files: one image, metadata, depth map"
        for name in record["files"]:
            left, right = os.path.join(whole, "items", item_id, name), os.path.join(banded, "items", item_id, name)
            if name.endswith((".png", ".exr")):
                assert np.array_equal(pixels(left), pixels(right)), "%s: the merged bands = one render, pixel for pixel" % name
            elif name.endswith(".json") and name != "item.json":
                assert sha256(left) == sha256(right), "%s: byte-identical" % name
    assert not os.path.exists(os.path.join(banded, "bands")) or not os.listdir(os.path.join(banded, "bands")), (
        "no band folder left after merging")
    # With alpha (+UA): the merge keeps it as stored (unassociated), pixel for pixel.
    # The sphere alone on nothing: alpha 1 on it, 0 around, fractions at its rim.
    alpha = write_spec(work, "alpha", focus="[1.0]", extra='povray_options = ["+UA", "Declare=No_Wall=1"]')
    a_whole, a_banded = os.path.join(work, "alpha_whole"), os.path.join(work, "alpha_banded")
    assert dataset(args, "run", alpha, "--out", a_whole, "-q").returncode == 0
    assert dataset(args, "run", alpha, "--out", a_banded, "--bands", "2", "-q").returncode == 0
    record = manifest(a_banded)[0]
    left = pixels(os.path.join(a_whole, "items", record["id"], record["image"]))
    right = pixels(os.path.join(a_banded, "items", record["id"], record["image"]))
    fractions = ((left[..., 3] > 0) & (left[..., 3] < 1)).sum()
    assert left.shape[2] == 4 and fractions > 10, "partly covered pixels at the sphere's rim (%d)" % fractions
    assert np.array_equal(left, right), "with alpha the merged bands = one render"
    # Diffraction convolves across rows: bands refused for it, with the reason.
    diffracted = write_spec(work, "diffracted", focus="[1.0]", extra="povray_options = [\"Declare=Diffract=1\"]")
    run = dataset(args, "run", diffracted, "--out", os.path.join(work, "diffracted"), "--bands", "2")
    assert run.returncode == 1 and "diffraction" in run.stderr and "without bands" in run.stderr, run.stderr[-1500:]


def _ids(out):
    return sorted(n for n in os.listdir(os.path.join(out, "items")) if not n.startswith("."))


def test_another_specs_data_set_is_refused_unless_replaced(args):
    work = os.path.join(args.work, "other_spec")
    shutil.rmtree(work, ignore_errors=True)
    first = write_spec(work, "first", focus="[1.0]")
    second = write_spec(work, "second", focus="[1.0, 1.5]")  # the first's 2 items, and 2 others
    out = os.path.join(work, "out")
    run = dataset(args, "run", first, "--out", out, "-q")
    assert run.returncode == 0, run.stderr
    kept = check_manifest(out, 2)
    times = {i: os.path.getmtime(os.path.join(out, "items", i, "item.json")) for i in kept}
    second_ids = [line.split(" ", 1)[0] for line in dataset(args, "items", second).stdout.splitlines()]
    assert len(second_ids) == 4 and set(kept) < set(second_ids), "the second spec shares the first's 2 items"

    # Another spec into the folder: refused, one line naming the folder's spec and --replace; nothing changes.
    run = dataset(args, "run", second, "--out", out)
    line = run.stderr.strip()
    assert run.returncode == 2 and "first.toml" in line and "--replace" in line and "\n" not in line, line
    assert sorted(check_manifest(out, 2)) == sorted(kept) and _ids(out) == sorted(kept), "the folder is untouched"

    # The same spec resumes, also with its [slurm] table edited (the same items).
    with open(first, "a") as f:
        f.write('\n[slurm]\npartition = "other"\n')
    run = dataset(args, "run", first, "--out", out)
    assert run.returncode == 0 and "2 of 2 items already finished" in run.stderr, run.stderr
    assert all(os.path.getmtime(os.path.join(out, "items", i, "item.json")) == t for i, t in times.items())

    # --replace: the folder becomes the second spec's; the items both specs have are kept, not rendered again.
    os.makedirs(os.path.join(out, "failed"), exist_ok=True)
    pt.write_text(os.path.join(out, "failed", "00009-deadbeef.log"), "an old item's log\n")
    run = dataset(args, "run", second, "--out", out, "--replace")
    assert run.returncode == 0 and "replaced" in run.stderr and "2 of 4 items already finished" in run.stderr, run.stderr
    assert sorted(check_manifest(out, 4)) == sorted(second_ids) == _ids(out)
    assert all(os.path.getmtime(os.path.join(out, "items", i, "item.json")) == t for i, t in times.items())
    assert os.listdir(os.path.join(out, "failed")) == [], "the other spec's failed logs are gone"
    record = pt.read_json(os.path.join(out, "dataset.json"))
    assert record["spec"] == os.path.abspath(second) and record["items"] == 4, record
    run = dataset(args, "run", first, "--out", out)
    assert run.returncode == 2 and "second.toml" in run.stderr, "now the first spec is the other one: " + run.stderr

    # A folder without a record (an older plenoptic-dataset's) holding another spec's items: refused too.
    os.remove(os.path.join(out, "dataset.json"))
    third = write_spec(work, "third", focus="[2.0]")
    run = dataset(args, "run", third, "--out", out)
    assert run.returncode == 2 and "--replace" in run.stderr and len(manifest(out)) == 4, run.stderr


def test_reserved_words_are_refused_before_rendering(args):
    work = os.path.join(args.work, "reserved")
    shutil.rmtree(work, ignore_errors=True)
    # `plenoptic` is the one word the fork adds to POV-Ray's table (docs/specification.md, section 6);
    # clock, x and sphere are POV-Ray's own. Camera words such as pitch are read inside the camera only.
    for text, key in (("[sweep]\nplenoptic = [1]", "sweep.plenoptic"),
                      ("[random]\ncount = 1\nclock = { uniform = [0, 1] }", "random.clock"),
                      ("[sweep]\nSphere_Size = [1]\nx = [1, 2]", "sweep.x"),
                      ("[sweep]\nsphere = [1]", "sweep.sphere")):
        spec = os.path.join(work, "reserved.toml")
        write_spec(work, "unused")
        pt.write_text(spec, 'scene = "scene.pov"\nwidth = 96\nheight = 72\n' + text + "\n")
        out = os.path.join(work, "out")
        run = dataset(args, "run", spec, "--out", out)
        line = run.stderr.strip()
        assert run.returncode == 2 and key in line and "reserved word" in line and "\n" not in line, (
            "%r: exit 2, one line naming %s (%s)" % (text, key, line[-1500:]))
        assert not os.path.exists(out), "nothing rendered, no folder made"
    spec = write_spec(work, "pitch", focus="[1.0]", extra="")
    with open(spec) as f:
        text = f.read().replace("count = 2", "count = 1").replace("[sweep]", "[sweep]\npitch = [0.1]")
    pt.write_text(spec, text)
    run = dataset(args, "run", spec, "--out", os.path.join(work, "pitch_out"), "-q")
    assert run.returncode == 0, "a camera word is not a global reserved word: " + run.stderr[-1500:]


def test_items_into_a_closed_pipe_end_quietly(args):
    work = os.path.join(args.work, "pipe")
    spec = write_spec(work, "many")
    with open(spec) as f:
        text = f.read().replace("count = 2", "count = 5000")
    pt.write_text(spec, text)
    env = dict(os.environ, PYTHONPATH=args.python, PLENOPTIC_POVRAY=args.povray)
    process = subprocess.Popen([sys.executable, "-m", "plenoptic_lf.dataset", "items", spec], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, env=env)
    first = process.stdout.readline()  # as `head -1`: read a line, then stop reading
    process.stdout.close()
    err = process.stderr.read().decode()
    process.wait(timeout=60)
    assert first.startswith(b"00000-"), first
    assert err == "", "no traceback, no message: %s" % err[-1500:]
    assert process.returncode == -signal.SIGPIPE, "ended by SIGPIPE as Unix tools are (%s)" % process.returncode
