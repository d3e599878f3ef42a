#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Golden-image regression test of one scene of tests/golden/scenes.json.

Renders the scene headless with our povray and compares, with the thresholds of its row in
scenes.json:
  - the image with OpenImageIO's idiff (-fail, -failpercent, -hardfail); on failure the
    render and an amplified difference image (idiff -abs -scale 16) are kept;
  - the depth EXR (scenes with `depth_map`), with idiff on the finite depths and numpy for
    the two special values (+inf: the chief ray left the scene; -1: no light reached the
    pixel), which idiff does not compare;
  - the metadata JSON field by field: same keys, same strings and nulls, numbers equal
    within abs + rel * |reference|;
  - and that a scene without a plenoptic camera writes neither metadata nor depth.

Regenerating the references (only after a change that is meant to change images, see
docs/testing.md): set PLENOPTIC_UPDATE_GOLDEN=1 in the environment of ctest
(`PLENOPTIC_UPDATE_GOLDEN=1 ctest -R '^golden_'`); it is the only switch.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES_DIR = os.path.join(HERE, "scenes")
REF_DIR = os.path.join(HERE, "references")
TABLE = os.path.join(HERE, "scenes.json")
UPDATE_VARIABLE = "PLENOPTIC_UPDATE_GOLDEN"

sys.path.insert(0, os.path.join(HERE, "..", "metadata"))
import metadata_schema  # noqa: E402  (tests/metadata: the strict reader and the schema check)


def load_table(path=TABLE):
    with open(path) as f:
        table = json.load(f)
    return table


def settings(table, name):
    """The scene's row merged over the defaults (one level deep for the threshold blocks)."""
    if name not in table["scenes"]:
        raise KeyError("scene '%s' is not in %s" % (name, TABLE))
    row = table["scenes"][name]
    out = {}
    for k, v in table["defaults"].items():
        out[k] = dict(v) if isinstance(v, dict) else v
    for k, v in row.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k].update(v)
        else:
            out[k] = v
    return out


def render(povray, name, s, out_dir, extra=()):
    """Renders scenes/<name>.pov into out_dir/<name>.png; returns the povray output text."""
    os.makedirs(out_dir, exist_ok=True)
    png = os.path.join(out_dir, name + ".png")
    for suffix in (".png", ".plenoptic.json", ".depth.exr"):
        p = os.path.join(out_dir, name + suffix)
        if os.path.exists(p):
            os.remove(p)
    cmd = [povray, "+I" + os.path.join(SCENES_DIR, name + ".pov"), "+O" + png,
           "+W%d" % s["width"], "+H%d" % s["height"], "-D", "-P", "+FN8", "-GS", "-GR",
           "+L" + SCENES_DIR] + list(s.get("options", [])) + list(extra)
    res = subprocess.run(cmd, cwd=out_dir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         timeout=600)
    text = res.stdout.decode(errors="replace")
    if res.returncode != 0 or not os.path.exists(png):
        raise RuntimeError("render of %s failed (exit %d):\n  %s\n%s"
                           % (name, res.returncode, " ".join(cmd), text[-3000:]))
    return text


def idiff(ref, new, t, diff_out):
    """Runs idiff with the thresholds t; returns (passed, exit code, idiff's report)."""
    exe = shutil.which("idiff")
    if not exe:
        raise RuntimeError("OpenImageIO's idiff is not installed (Debian: openimageio-tools)")
    cmd = [exe, "-fail", str(t["fail"]), "-failpercent", str(t["failpercent"]),
           "-hardfail", str(t["hardfail"]), "-abs", "-scale", "16", "-o", diff_out, ref, new]
    res = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    text = res.stdout.decode(errors="replace").strip()
    # 0: identical within -fail; 1: warning only; 2: failure; 3: size mismatch; 4: file error.
    return res.returncode in (0, 1), res.returncode, text


def compare_json(ref, new, rel, absolute, path="", out=None):
    """Every difference between two JSON values, as 'path: reference vs measured' lines."""
    if out is None:
        out = []
    if isinstance(ref, dict) and isinstance(new, dict):
        for k in sorted(set(ref) | set(new)):
            p = path + "." + k if path else k
            if k not in new:
                out.append("%s: in the reference (%r), missing from the render" % (p, ref[k]))
            elif k not in ref:
                out.append("%s: new field (%r), not in the reference" % (p, new[k]))
            else:
                compare_json(ref[k], new[k], rel, absolute, p, out)
    elif isinstance(ref, list) and isinstance(new, list):
        if len(ref) != len(new):
            out.append("%s: %d elements in the reference, %d measured (%r vs %r)" % (path, len(ref), len(new), ref, new))
        else:
            for i, (a, b) in enumerate(zip(ref, new)):
                compare_json(a, b, rel, absolute, "%s[%d]" % (path, i), out)
    elif isinstance(ref, bool) or isinstance(new, bool) or ref is None or new is None \
            or isinstance(ref, str) or isinstance(new, str):
        if ref != new or type(ref) is not type(new):
            out.append("%s: reference %r, measured %r" % (path, ref, new))
    elif isinstance(ref, (int, float)) and isinstance(new, (int, float)):
        tol = absolute + rel * abs(ref)
        if not (abs(ref - new) <= tol):
            out.append("%s: reference %.17g, measured %.17g (|difference| %.3g > tolerance %.3g)"
                       % (path, ref, new, abs(ref - new), tol))
    else:
        out.append("%s: reference %r, measured %r (different types)" % (path, ref, new))
    return out


def compare_depth(ref, new, t, diff_out):
    """Depth maps: special values must match exactly, finite depths within t (idiff)."""
    import numpy as np
    import OpenImageIO as oiio

    def read(p):
        buf = oiio.ImageBuf(p)
        if buf.has_error:
            raise RuntimeError("cannot read %s: %s" % (p, buf.geterror()))
        return buf.get_pixels(oiio.FLOAT)

    a, b = read(ref), read(new)
    problems = []
    if a.shape != b.shape:
        return ["depth map size %s, reference %s" % (b.shape, a.shape)]
    for label, fa, fb in (("+inf (chief ray leaves the scene)", np.isposinf(a), np.isposinf(b)),
                          ("-1 (no light)", a == -1, b == -1),
                          ("NaN", np.isnan(a), np.isnan(b))):
        n = int(np.count_nonzero(fa != fb))
        if n:
            ys, xs = np.nonzero((fa != fb)[..., 0])
            problems.append("%d pixel(s) differ in being %s, first at (x %d, y %d): reference %g, measured %g"
                            % (n, label, xs[0], ys[0], a[ys[0], xs[0], 0], b[ys[0], xs[0], 0]))
    if np.isnan(b).any():
        problems.append("the depth map holds NaN")
    ok, code, text = idiff(ref, new, t, diff_out)
    if not ok:
        problems.append("idiff on the depth map (exit %d):\n%s" % (code, text))
    return problems


def run(povray, name, work, update):
    table = load_table()
    s = settings(table, name)
    out_dir = os.path.join(work, name)
    if os.path.exists(out_dir):
        shutil.rmtree(out_dir)
    render(povray, name, s, out_dir)
    png = os.path.join(out_dir, name + ".png")
    meta = os.path.join(out_dir, name + ".plenoptic.json")
    depth = os.path.join(out_dir, name + ".depth.exr")
    ref_png = os.path.join(REF_DIR, name + ".png")
    ref_meta = os.path.join(REF_DIR, name + ".plenoptic.json")
    ref_depth = os.path.join(REF_DIR, name + ".depth.exr")
    expect_meta = s.get("metadata_file", True)
    expect_depth = bool(s.get("depth_map", False))

    failures = []
    # What the render must write, before anything is compared or stored.
    if expect_meta != os.path.exists(meta):
        failures.append("metadata %s: expected %s" % (meta, "to exist" if expect_meta else "none"))
    if expect_depth != os.path.exists(depth):
        failures.append("depth map %s: expected %s" % (depth, "to exist" if expect_depth else "none"))
    if failures:
        for f in failures:
            print("FAIL %s: %s" % (name, f))
        return 1

    if update:
        os.makedirs(REF_DIR, exist_ok=True)
        shutil.copyfile(png, ref_png)
        for new, ref, wanted in ((meta, ref_meta, expect_meta), (depth, ref_depth, expect_depth)):
            if wanted:
                shutil.copyfile(new, ref)
            elif os.path.exists(ref):
                os.remove(ref)
        print("UPDATED references of %s in %s (%s=1): look at %s before committing it"
              % (name, REF_DIR, UPDATE_VARIABLE, ref_png))
        return 0

    for ref, wanted in ((ref_png, True), (ref_meta, expect_meta), (ref_depth, expect_depth)):
        if wanted and not os.path.exists(ref):
            print("FAIL %s: no reference %s; create it with %s=1 (see docs/testing.md)"
                  % (name, ref, UPDATE_VARIABLE))
            return 1

    img_t = s["image"]
    diff_png = os.path.join(out_dir, name + ".diff.png")
    ok, code, report = idiff(ref_png, png, img_t, diff_png)
    print("image: idiff -fail %s -failpercent %s -hardfail %s: exit %d"
          % (img_t["fail"], img_t["failpercent"], img_t["hardfail"], code))
    if not ok:
        failures.append("image differs from %s (idiff exit %d)\n%s\n  render: %s\n  difference x16: %s"
                        % (ref_png, code, report, png, diff_png))
    elif os.path.exists(diff_png):
        os.remove(diff_png)

    if expect_meta:
        # Both read strictly and checked against docs/metadata.schema.json.
        try:
            r = metadata_schema.load(ref_meta)
            m = metadata_schema.load(meta)
        except metadata_schema.MetadataError as e:
            print("FAIL %s: %s" % (name, e))
            return 1
        mt = s["metadata"]
        diffs = compare_json(r, m, mt["rel"], mt["abs"])
        print("metadata: %d field difference(s) beyond abs %g + rel %g" % (len(diffs), mt["abs"], mt["rel"]))
        if diffs:
            failures.append("metadata differs from %s:\n  %s" % (ref_meta, "\n  ".join(diffs)))

    if expect_depth:
        depth_diff = os.path.join(out_dir, name + ".depth.diff.exr")
        problems = compare_depth(ref_depth, depth, s["depth"], depth_diff)
        print("depth: %d problem(s)" % len(problems))
        if problems:
            failures.append("depth map differs from %s:\n  %s\n  render: %s\n  difference x16: %s"
                            % (ref_depth, "\n  ".join(problems), depth, depth_diff))
        elif os.path.exists(depth_diff):
            os.remove(depth_diff)

    if failures:
        for f in failures:
            print("FAIL %s: %s" % (name, f))
        print("If this change is intended, regenerate with %s=1 (docs/testing.md) and look at the new images."
              % UPDATE_VARIABLE)
        return 1
    print("ok   %s" % name)
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--povray", required=True)
    ap.add_argument("--scene", required=True, help="name of a row of scenes.json")
    ap.add_argument("--work", required=True, help="scratch directory")
    args = ap.parse_args()
    # The one switch that regenerates references (docs/testing.md).
    update = os.environ.get(UPDATE_VARIABLE, "") not in ("", "0")
    try:
        return run(args.povray, args.scene, os.path.abspath(args.work), update)
    except (RuntimeError, KeyError, subprocess.TimeoutExpired) as e:
        print("FAIL %s: %s" % (args.scene, e))
        return 1


if __name__ == "__main__":
    sys.exit(main())
