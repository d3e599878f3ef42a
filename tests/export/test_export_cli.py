# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-export, the command (docs/export/README.md): its refusals (an unknown format names the
formats there are; an image without its metadata names the file it looked for; an option the
format does not take names those it does), and its all-or-nothing output: a format that fails or
is interrupted half-way leaves the output folder as it was and no staging folder behind; one that
succeeds has its files moved into the folder, listed on standard output. Renders nothing."""
import os
import subprocess
import sys
import types

import numpy as np
import pytest


def run_export(args, *argv):
    return subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-export"), *argv],
                          capture_output=True, text=True, cwd=args.work, timeout=60)


def one_error_line(run):
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1 and lines[0].startswith("plenoptic-export: error: "), \
        "exit %d, stderr %r" % (run.returncode, run.stderr)
    return lines[0]


def leftovers(folder):
    """Every entry of folder's parent that names folder (the folder itself, a staging folder)."""
    parent, name = os.path.split(os.path.abspath(folder))
    return sorted(e for e in os.listdir(parent) if name in e)


def small_png(path):
    from PIL import Image
    Image.fromarray(np.full((6, 8, 3), 128, np.uint8)).save(path)


def test_unknown_format_names_the_formats(args):
    from plenoptic_lf.export import FORMATS
    out = os.path.join(args.work, "unknown_format")
    run = run_export(args, "nothing.png", "--to", "lytro-lfp", out)
    line = one_error_line(run)
    assert "--to lytro-lfp: no such format" in line, line
    for name in FORMATS:
        assert name in line, "the refusal names the format %s: %s" % (name, line)
    assert not leftovers(out), leftovers(out)


def test_help_lists_every_format_with_its_summary(args):
    from plenoptic_lf.export import FORMATS
    run = run_export(args, "--help")
    assert run.returncode == 0 and run.stdout.startswith("usage: plenoptic-export"), run.stderr
    for name, module in FORMATS.items():
        assert module.SUMMARY.strip() and "\n" not in module.SUMMARY, name
        assert name in run.stdout and module.SUMMARY[:40] in " ".join(run.stdout.split()), name


def test_missing_metadata_is_named(args):
    from plenoptic_lf.export import FORMATS
    if not FORMATS:
        pytest.skip("no format registered")
    image = os.path.join(args.work, "lonely.png")
    small_png(image)
    out = os.path.join(args.work, "lonely_out")
    line = one_error_line(run_export(args, image, "--to", sorted(FORMATS)[0], out))
    assert "lonely.plenoptic.json" in line and "does not exist" in line, line
    assert not leftovers(out), leftovers(out)


def test_missing_image_is_named(args):
    from plenoptic_lf.export import FORMATS
    if not FORMATS:
        pytest.skip("no format registered")
    out = os.path.join(args.work, "missing_out")
    line = one_error_line(run_export(args, "no-such-render.png", "--to", sorted(FORMATS)[0], out))
    assert "no-such-render.png" in line and "does not exist" in line, line


def test_option_the_format_does_not_take(args):
    from plenoptic_lf.export import FORMATS
    if not FORMATS:
        pytest.skip("no format registered")
    name = sorted(FORMATS)[0]
    line = one_error_line(run_export(args, "x.png", "--to", name, os.path.join(args.work, "o"), "-O", "colour=blue"))
    assert "-O colour" in line and ("the format %s takes" % name) in line, line
    line = one_error_line(run_export(args, "x.png", "--to", name, os.path.join(args.work, "o"), "-O", "novalue"))
    assert "NAME=VALUE" in line, line


class _FakeRender:
    def __init__(self, image_path, metadata_path=None, encoding="auto", progress=None):
        self.metadata_path = image_path + ".json"


def _fake_format(behaviour):
    """A format module whose export writes two files (one in a sub-folder), then does `behaviour`:
    'ok' returns them, 'interrupt' raises KeyboardInterrupt, 'refuse' an ExportError."""
    from plenoptic_lf.export import ExportError

    def export(render, out_dir, **options):
        written = []
        for rel in ("a.txt", os.path.join("sub", "b.txt")):
            path = out_dir / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text("written by the fake format\n")
            written.append(path)
        if behaviour == "interrupt":
            raise KeyboardInterrupt
        if behaviour == "refuse":
            raise ExportError("the fake format cannot express this render")
        return written

    return types.SimpleNamespace(SUMMARY="a fake format of the test", OPTIONS={}, export=export)


@pytest.mark.parametrize("behaviour, status", [("interrupt", 130), ("refuse", 2), ("ok", 0)])
def test_output_is_all_or_nothing(args, monkeypatch, capsys, behaviour, status):
    from plenoptic_lf.export import cli
    monkeypatch.setattr(cli, "Render", _FakeRender)
    monkeypatch.setitem(cli.FORMATS, "fake", _fake_format(behaviour))
    monkeypatch.setattr(cli, "require_openimageio", lambda: None)
    out = os.path.join(args.work, "all_or_nothing_" + behaviour)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "keep.txt"), "w") as f:
        f.write("the user's own file\n")
    for leftover in ("a.txt", os.path.join("sub", "b.txt")):
        if os.path.exists(os.path.join(out, leftover)):
            os.remove(os.path.join(out, leftover))
    assert cli.main(["render.png", "--to", "fake", out, "-q"]) == status
    captured = capsys.readouterr()
    found = sorted(os.path.relpath(os.path.join(d, n), out) for d, _, files in os.walk(out) for n in files)
    assert leftovers(out) == [os.path.basename(out)], "no staging folder is left: %s" % leftovers(out)
    if behaviour == "ok":
        assert found == sorted(["a.txt", "keep.txt", os.path.join("sub", "b.txt")]), found
        assert captured.out.split() == [os.path.join(out, "a.txt"), os.path.join(out, "sub", "b.txt")], captured.out
    else:
        assert found == ["keep.txt"], "after %s the folder is as it was: %s" % (behaviour, found)
        if behaviour == "interrupt":
            assert "interrupted: nothing written" in captured.err, captured.err
        else:
            assert "the fake format cannot express this render" in captured.err, captured.err


def test_broken_metadata_is_named(args):
    from plenoptic_lf.export import FORMATS
    image = os.path.join(args.work, "broken.png")
    small_png(image)
    with open(os.path.join(args.work, "broken.plenoptic.json"), "w") as f:
        f.write('{"format": "povray-plenoptic", ')
    out = os.path.join(args.work, "broken_out")
    line = one_error_line(run_export(args, image, "--to", sorted(FORMATS)[0], out))
    assert "broken.plenoptic.json: " in line, line
    assert not leftovers(out), leftovers(out)
