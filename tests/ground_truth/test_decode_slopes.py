# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode --slopes START:STOP:COUNT: the documented form works, and a malformed value is
refused with a message that names the option and the form.

  - `--slopes -0.8:0.8:17` (the documentation's example: a value that starts with '-', which
    argparse alone takes for an option), `--slopes=-0.5:0.5:5` and the abbreviation
    `--slo -0.3:0.6:4` decode with exactly numpy.linspace(START, STOP, COUNT) as the sweep
    (lightfield.json's "slopes");
  - `a:1:5`, `1:2`, `0:1:x`, `0:1:2.5`, `1:0:5`, `0:1:1`, `nan:1:3`: exit 2, one line
    'plenoptic-decode: error: ...' naming --slopes and START:STOP:COUNT, no Python wording
    ("could not convert"), no traceback, nothing written;
  - `--slopes -q` (a missing value) is still argparse's "expected one argument".
"""

import json
import os
import shutil
import subprocess

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
}
sphere { 0, 0.3 pigment { checker rgb 1 rgb <1, 0.2, 0.1> scale 0.1 } finish { emission 1 diffuse 0 } }
"""


@pytest.fixture(scope="module")
def png(args):
    return pt.render_ground_truth(args.povray, args.work, "slopes", SCENE, 96, 72)[0]


def run(args, png, options, name):
    out = os.path.join(args.work, "slopes_" + name + ".lightfield")
    shutil.rmtree(out, ignore_errors=True)
    decode = pt.decoder(args.tools) + [png, "--no-gif", "--no-npy", "-q"]
    return subprocess.run(decode + ["-o", out] + options, capture_output=True, text=True), out


GOOD = [
    ("documented", ["--slopes", "-0.8:0.8:17"], (-0.8, 0.8, 17)),
    ("equals", ["--slopes=-0.5:0.5:5"], (-0.5, 0.5, 5)),
    ("abbreviated", ["--slo", "-0.3:0.6:4"], (-0.3, 0.6, 4)),
]


@pytest.mark.parametrize("name, options, sweep", GOOD, ids=[c[0] for c in GOOD])
def test_sweep_as_asked(args, png, name, options, sweep):
    start, stop, count = sweep
    result, out = run(args, png, options, name)
    description = os.path.join(out, "lightfield.json")
    slopes = json.load(open(description))["slopes"] if os.path.exists(description) else None
    want = np.linspace(start, stop, count)
    assert (result.returncode == 0 and slopes is not None and len(slopes) == count
            and np.allclose(slopes, want, rtol=0, atol=1e-12)), (
        "%s: exit %d (want 0), sweep %s (want linspace(%g, %g, %d))%s"
        % (" ".join(options), result.returncode, slopes, start, stop, count,
           "; stderr %r" % result.stderr.strip()[-300:] if result.returncode else ""))


@pytest.mark.parametrize("value", ["a:1:5", "1:2", "0:1:x", "0:1:2.5", "1:0:5", "0:1:1", "nan:1:3"])
def test_bad_sweep_refused(args, png, value):
    result, out = run(args, png, ["--slopes", value], "bad")
    lines = [l for l in result.stderr.splitlines() if l.strip()]
    assert (result.returncode == 2 and len(lines) == 1 and lines[0].startswith("plenoptic-decode: error:")
            and "--slopes" in lines[0] and "START:STOP:COUNT" in lines[0] and value in lines[0]
            and "could not convert" not in lines[0] and "invalid literal" not in lines[0]
            and "Traceback" not in result.stderr
            and not os.path.exists(os.path.join(out, "contact_sheet.png"))), (
        "--slopes %s: exit %d (want 2), stderr %r (want one line naming --slopes, START:STOP:COUNT "
        "and the value)" % (value, result.returncode, result.stderr.strip()[-400:]))


def test_missing_sweep_value(args, png):
    result, _ = run(args, png, ["--slopes", "-q"], "missing")
    assert (result.returncode == 2 and "--slopes" in result.stderr and "expected one argument" in result.stderr), (
        "--slopes -q (no value): exit %d, stderr %r (want argparse's 'expected one argument')"
        % (result.returncode, result.stderr.strip()[-300:]))
