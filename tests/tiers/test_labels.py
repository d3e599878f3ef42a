# SPDX-License-Identifier: AGPL-3.0-or-later
"""Every ctest test carries the labels docs/testing.md documents ("Test tiers and labels").

The documented labels are read from that section's table (first column: the label or labels in
backquotes; second: its group, kind, tier, topic or family). The tests and their labels are what
ctest itself reports for the build directory (`ctest --show-only=json-v1`, which also runs the
GoogleTest discovery), so a test added anywhere without its labels fails here, named. Rules:

  - exactly one kind label (unit or render) and exactly one family label;
  - no label outside the table, and every label of the table carried by some test;
  - smoke (a render of the quick tier, which tools/test --quick runs with the unit tests) only on
    a render test, and never with slow or network.

Renders nothing; needs the build directory (--build-dir) and ctest (beside --cmake).
"""
import json
import os
import re
import shutil
import subprocess
import tempfile

import pytest

SECTION = "## Test tiers and labels"
GROUPS = ("kind", "tier", "topic", "family")


def documented_labels(testing_md):
    """{label: group} from the first table under SECTION in docs/testing.md."""
    with open(testing_md, encoding="utf-8") as f:
        lines = f.read().splitlines()
    assert SECTION in lines, "%s has no section %r" % (testing_md, SECTION)
    labels = {}
    in_table = False
    for line in lines[lines.index(SECTION) + 1:]:
        if line.startswith("## "):
            break
        if not line.startswith("|"):
            if in_table:
                break
            continue
        in_table = True
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) < 2 or cells[1] not in GROUPS:
            continue  # the header and the rule below it
        for name in re.findall(r"`([^`]+)`", cells[0]):
            assert name not in labels, "label %r is in the table twice" % name
            labels[name] = cells[1]
    assert labels, "no label rows in the table under %r in %s" % (SECTION, testing_md)
    return labels


def ctest_labels(ctest, build_dir):
    """{test name: set of labels}, as ctest reports them for build_dir. ctest runs in a scratch
    directory whose CTestTestfile.cmake names build_dir: even a listing writes
    Testing/Temporary/LastTest.log, which must stay the build's last real run (tools/test-times)."""
    with tempfile.TemporaryDirectory(prefix="tiers-labels-") as scratch:
        with open(os.path.join(scratch, "CTestTestfile.cmake"), "w", encoding="utf-8") as f:
            f.write("subdirs([==[%s]==])\n" % os.path.abspath(build_dir))
        run = subprocess.run([ctest, "--show-only=json-v1"], cwd=scratch, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, universal_newlines=True, timeout=300)
    assert run.returncode == 0, "ctest --show-only=json-v1 in %s failed (exit %d): %s" % (
        build_dir, run.returncode, run.stderr.strip()[-500:])
    tests = {}
    for test in json.loads(run.stdout)["tests"]:
        labels = set()
        for prop in test.get("properties", []):
            if prop["name"] == "LABELS":
                labels.update(prop["value"])
        tests[test["name"]] = labels
    return tests


def problems(tests, documented):
    """One line per broken rule: `tests` {name: labels}, `documented` {label: group}."""
    out = []
    of = lambda group: {l for l, g in documented.items() if g == group}
    kinds, families = of("kind"), of("family")
    for name in sorted(tests):
        labels = tests[name]
        shown = ", ".join(sorted(labels)) or "none"
        for group, allowed in (("kind", kinds), ("family", families)):
            if len(labels & allowed) != 1:
                out.append("%s: needs exactly one %s label (one of %s); has: %s"
                           % (name, group, ", ".join(sorted(allowed)), shown))
        for label in sorted(labels - set(documented)):
            out.append("%s: label %r is not in docs/testing.md's table" % (name, label))
        excluded = labels & {"slow", "network"}
        if "smoke" in labels and excluded:
            out.append("%s: smoke and %s: the quick tier runs no slow or network test"
                       % (name, ", ".join(sorted(excluded))))
        if "smoke" in labels and "render" not in labels:
            out.append("%s: smoke marks the renders of the quick tier (unit tests are in it anyway)" % name)
    used = set().union(*tests.values()) if tests else set()
    for label in sorted(set(documented) - used):
        out.append("label %r of docs/testing.md's table is carried by no test" % label)
    return out


def test_documented_table(args):
    documented = documented_labels(os.path.join(args.source_dir, "docs", "testing.md"))
    for label in ("unit", "render", "smoke", "slow", "network"):
        assert label in documented, "docs/testing.md's table lacks %r (has %s)" % (label, sorted(documented))
    assert {documented["unit"], documented["render"]} == {"kind"}, "unit and render are the kinds"


def test_every_test_is_labelled(args):
    ctest = os.path.join(os.path.dirname(args.cmake), "ctest") if os.sep in args.cmake else shutil.which("ctest")
    assert ctest and os.path.exists(ctest), "no ctest beside %s" % args.cmake
    assert os.path.exists(os.path.join(args.build_dir, "CTestTestfile.cmake")), (
        "%s is not a configured build directory" % args.build_dir)
    documented = documented_labels(os.path.join(args.source_dir, "docs", "testing.md"))
    tests = ctest_labels(ctest, args.build_dir)
    assert "tiers_labels" in tests, "ctest does not list this test itself: %d tests read" % len(tests)
    found = problems(tests, documented)
    assert not found, "%d of %d tests break the labelling rules:\n%s" % (
        len({p.split(":")[0] for p in found}), len(tests), "\n".join(found))


DOC = {"unit": "kind", "render": "kind", "smoke": "tier", "slow": "tier", "network": "tier",
       "golden": "family", "camera": "family"}


@pytest.mark.parametrize("labels, expected", [
    (set(), ["needs exactly one kind", "needs exactly one family"]),
    ({"golden"}, ["needs exactly one kind"]),
    ({"render"}, ["needs exactly one family"]),
    ({"unit", "render", "golden"}, ["needs exactly one kind"]),
    ({"render", "golden", "camera"}, ["needs exactly one family"]),
    ({"render", "golden", "quick"}, ["'quick' is not in"]),
    ({"render", "golden", "smoke", "slow"}, ["smoke and slow"]),
    ({"render", "golden", "smoke", "network"}, ["smoke and network"]),
    ({"unit", "golden", "smoke"}, ["smoke marks the renders"]),
    ({"unit", "golden"}, []),
    ({"unit", "golden", "slow", "network"}, []),
    ({"render", "golden", "smoke"}, []),
])
def test_rules_bite(labels, expected):
    """The rules find each kind of mistake in a made-up test beside one that carries every label."""
    tests = {"x": labels, "others": {"unit", "render", "smoke", "slow", "network", "golden", "camera"}}
    found = [p for p in problems(tests, DOC) if p.startswith("x:")]
    assert len(found) == len(expected) and all(e in f for e, f in zip(expected, found)), (
        "labels %s: expected problems %s, found %s" % (sorted(labels), expected, found))


def test_unused_label_bites():
    """A label of the table that no test carries is named."""
    unused = problems({"x": {"unit", "golden"}}, DOC)
    assert unused == ["label %r of docs/testing.md's table is carried by no test" % l
                      for l in ("camera", "network", "render", "slow", "smoke")], unused
