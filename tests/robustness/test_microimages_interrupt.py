# SPDX-License-Identifier: AGPL-3.0-or-later
"""Ctrl-C while the microimage centres are being computed (after the image is written, before the
metadata): the program stops promptly, writes no microimages file, says so, and leaves the
metadata complete with "microimages": null and no temporary file behind.

The camera: the 22 mm wide-angle of lenses/ with 15 000 thin microlenses over a 1440 x 960 raw at
one sample, so that the render takes a second or two and the microimage centres about ten
seconds on two threads (docs/real-lenses.md, "Microimage centres").
"""
import os
import signal
import subprocess
import time

import plenoptic_testing as pt

LENSES_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "lenses"))

SCENE = """#version 3.7;
global_settings { assumed_gamma 1 }
background { rgb 1 }
camera { plenoptic
  location <0, 0, -4> look_at <0, 0, 0>
  main_lens { lens_file "wide_angle_22mm_laikin_f3.5.dat" f_number 5.6 focus_distance 4 }
  microlens_array { hexagonal pitch 0.2 focal_length 0.8 distance 0.8 }
  sensor { pixel_size <0.02, 0.02> }
  samples 1
}
"""


def test_interrupt_during_microimage_centres(args):
    work = os.path.join(args.work, "microimages_interrupt")
    os.makedirs(work, exist_ok=True)
    for name in os.listdir(work):
        os.remove(os.path.join(work, name))
    pov = os.path.join(work, "scene.pov")
    pt.write_text(pov, SCENE)
    png = os.path.join(work, "scene.png")
    proc = subprocess.Popen([args.povray, "+I" + pov, "+O" + png, "+W1440", "+H960", "-D", "+WT2",
                             "+L" + LENSES_DIR], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=work)
    deadline = time.time() + 120
    while not os.path.exists(png) and proc.poll() is None and time.time() < deadline:
        time.sleep(0.05)
    assert os.path.exists(png) and proc.poll() is None, "the image was not written, or the program ended first"
    time.sleep(0.5)  # into the microimage centres
    assert proc.poll() is None, "the microimage centres were done too soon for this test to mean anything"
    sent = time.time()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    took = time.time() - sent
    err = err.decode("utf-8", "replace")
    print("stopped %.2f s after SIGINT, exit %d" % (took, proc.returncode))
    # Promptly: a lens takes about a millisecond; POV-Ray's own shutdown polls every 10 ms.
    assert took < 3.0, (took, err)
    assert "cancelled: no microimage centres written" in err, err
    assert not os.path.exists(os.path.join(work, "scene.microimages.csv"))
    meta = pt.load_metadata(os.path.join(work, "scene.plenoptic.json"))
    assert meta["microimages"] is None
    assert meta["main_lens"]["distortion_profile"] is not None
    leftovers = [n for n in os.listdir(work) if n.startswith(".plenoptic-")]
    assert not leftovers, leftovers
