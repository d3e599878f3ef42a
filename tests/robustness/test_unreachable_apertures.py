# SPDX-License-Identifier: AGPL-3.0-or-later
"""Apertures a real lens cannot deliver, and white_image f_numbers that cannot be written: each is
refused at parse time, as tests/robustness/test_malformed_cameras.py checks refusals (the file
and the marked line, the message's fragments, nothing left behind). docs/real-lenses.md ("The
aperture that limits the beam") and docs/sensor.md ("White images") promise them.

- `f_number 2` and `aperture 21` on the 22 mm f/3.5 wide-angle of lenses/: at that stop the rear
  group's rims, not the stop, would limit the beam (the lens reaches about f/2.74); refused at the
  keyword, naming the value, the limiting row and the fastest f-number.
- `f_number 0.01` on a singlet: the "absurd stop" (it rendered black).
- `thick_lens` (the paraxial equivalent) is refused the same way.
- `white_image f_numbers` with a value the lens cannot deliver, at the f_numbers keyword; with a
  value listed twice (each names its own file); with more values than the documented maximum.
- The documented maximum is the code's: docs/sensor.md's "1 to N values" renders with N values
  (they are all written) and refuses N + 1.
"""
import os
import re
import sys

import pytest

import plenoptic_testing as pt

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_malformed_cameras import MAIN, MARK, SAMPLES, camera, main_with, refused  # noqa: E402

LAIKIN = 'lens_file "wide_angle_22mm_laikin_f3.5.dat"'
SINGLET = ("prescription {", "  stop { thickness 5 aperture 8 }",
           "  surface { radius 60 thickness 4 ior 1.5 aperture 30 }",
           "  surface { radius -60 thickness 0 ior 1 aperture 30 }", "}")
FASTEST = "fastest f-number the lens reaches is"

CASES = [
    ("f_number 2 on the f/3.5 wide-angle",
     camera(main=main_with(LAIKIN, "f_number 2  " + MARK, "focus_distance 2.5")),
     ["f_number 2", "cannot deliver", "surface 9 (line", "wide_angle_22mm_laikin_f3.5.dat", FASTEST, "2.74",
      "at most 15.3"],
     "the rear group's rims limit the beam from a stop of 15.37 mm on"),
    ("f_number 2 before the lens_file",
     camera(main=main_with("f_number 2  " + MARK, LAIKIN, "focus_distance 2.5")),
     ["f_number 2", FASTEST], "reported at the keyword wherever it stands in the block"),
    ("aperture 21 on the f/3.5 wide-angle",
     camera(main=main_with(LAIKIN, "aperture 21  " + MARK, "focus_distance 2.5")),
     ["aperture 21", "cannot deliver", FASTEST, "at most 15.3"], "the stop diameter itself"),
    ("thick_lens f_number 2",
     camera(main=main_with("thick_lens", LAIKIN, "f_number 2  " + MARK, "focus_distance 2.5")),
     ["f_number 2", FASTEST], "the paraxial equivalent has the same limiting aperture"),
    ("f_number 0.01 on a singlet (the absurd stop)",
     camera(main=main_with(*(SINGLET + ("f_number 0.01  " + MARK, "focus_distance 2")))),
     ["f_number 0.01", "surface 2 (scene line", FASTEST], "it rendered black"),
    ("white_image f_numbers beyond the lens",
     camera(main=main_with(LAIKIN, "focus_distance 2.5"), extra=SAMPLES + "\n  white_image f_numbers <4, 2>  " + MARK),
     ["white_image f_numbers 2", "f_number 2", FASTEST], "each white image's f-number as f_number N"),
    ("white_image f_numbers listed twice",
     camera(extra=SAMPLES + "\n  white_image f_numbers <2.8, 4, 2.8>  " + MARK),
     ["white_image f_numbers", "2.8 twice", "values 1 and 3", ".white.f2.8.png"],
     "each f-number names its own file"),
    ("white_image f_numbers too many",
     camera(extra=SAMPLES + "\n  white_image f_numbers <" + ", ".join(str(2 + k) for k in range(17)) + ">  " + MARK),
     ["white_image f_numbers", "at most 16"], "the documented maximum"),
]


@pytest.mark.parametrize("index", range(len(CASES)), ids=[c[0] for c in CASES])
def test_unreachable_aperture(args, index):
    """ctest robustness_unreachable_apertures."""
    refused(args, "unreachable", index, *CASES[index])


def documented_maximum():
    text = open(os.path.join(pt.SOURCE_DIR, "docs", "sensor.md")).read()
    found = re.search(r"\*\*`f_numbers`\*\* \(1 to (\d+) values", text)
    assert found, "docs/sensor.md no longer says how many f_numbers a white_image takes"
    return int(found.group(1))


def test_white_image_f_numbers_count_matches_docs(args):
    """The documented most values render (each white image is written); one more is refused."""
    most = documented_maximum()
    work = os.path.join(args.work, "count")
    values = [1.5 + 0.5 * k for k in range(most)]
    block = camera(main=MAIN, extra=SAMPLES + "\n  white_image f_numbers <%s>" % ", ".join("%g" % v for v in values))
    path = pt.render(args.povray, work, "most", pt.scene_text(block), 16, 12)
    written = pt.metadata_of(path)["white_images"]
    assert [w["f_number"] for w in written] == pytest.approx(values), written
    assert all(os.path.exists(os.path.join(work, w["file"])) for w in written)
    too_many = camera(main=MAIN, extra=SAMPLES + "\n  white_image f_numbers <%s>" %
                      ", ".join("%g" % (1.5 + 0.5 * k) for k in range(most + 1)))
    status, output = pt.render(args.povray, work, "too_many", pt.scene_text(too_many), 16, 12, expect_failure=True)
    # POV-Ray wraps its messages at 80 columns, wherever the file's path puts the break.
    assert status != 0 and "at most %d" % most in " ".join(output.split()), output[-2000:]
