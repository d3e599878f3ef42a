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
import os
import shutil

import numpy as np
import pytest

import plenoptic_testing as pt

REF_DIR = os.path.join(pt.GOLDEN_DIR, "references")
UPDATE_VARIABLE = "PLENOPTIC_UPDATE_GOLDEN"
SCENES = sorted(pt.golden_table()["scenes"])


def idiff(ref, new, t, diff_out):
    """Runs idiff with the thresholds t; returns (passed, exit code, idiff's report)."""
    code, text = pt.idiff(ref, new, ["-fail", str(t["fail"]), "-failpercent", str(t["failpercent"]),
                                     "-hardfail", str(t["hardfail"])], diff_out=diff_out)
    # 0: identical within -fail; 1: warning only; 2: failure; 3: size mismatch; 4: file error.
    return code in (0, 1), code, text


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
    a, b = pt.read_pixels(ref), pt.read_pixels(new)
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


@pytest.mark.parametrize("name", SCENES)
def test_golden(args, name):
    # The one switch that regenerates references (docs/testing.md).
    update = os.environ.get(UPDATE_VARIABLE, "") not in ("", "0")
    povray, work = args.povray, args.work
    s = pt.golden_settings(pt.golden_table(), name)
    out_dir = os.path.join(work, name)
    if os.path.exists(out_dir):
        shutil.rmtree(out_dir)
    pt.render_golden(povray, name, s, out_dir)
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
    assert not failures, "%s: %s" % (name, "; ".join(failures))

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
        return

    for ref, wanted in ((ref_png, True), (ref_meta, expect_meta), (ref_depth, expect_depth)):
        assert not wanted or os.path.exists(ref), ("%s: no reference %s; create it with %s=1 (see docs/testing.md)"
                                                   % (name, ref, UPDATE_VARIABLE))

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
        r = pt.load_metadata(ref_meta)
        m = pt.load_metadata(meta)
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

    assert not failures, ("%s:\n%s\nIf this change is intended, regenerate with %s=1 (docs/testing.md) and look at "
                          "the new images." % (name, "\n".join(failures), UPDATE_VARIABLE))

