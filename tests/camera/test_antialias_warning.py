# SPDX-License-Identifier: AGPL-3.0-or-later
"""`+A` on a plenoptic render: one warning, and the image is the one without `+A`.

The camera integrates each pixel itself (its `samples`); POV-Ray's supersampling is not used
(docs/camera.md, Sampling). A user who asks for it must be told, once, not ignored silently.
A stock perspective render with +A must print no such warning.
"""
import numpy as np

import plenoptic_testing as pt

WARNING = "antialiasing (+A) is ignored"

SCENE = """#version 3.7;
global_settings { assumed_gamma 1.0 }
light_source { <-3, 6, -4> rgb 1 }
plane { y, 0 pigment { checker rgb 0.1 rgb 0.9 scale 0.2 } }
sphere { <0, 0.4, 0>, 0.4 pigment { rgb <0.9, 0.3, 0.2> } }
camera {
  %s
}
"""
PLENOPTIC = """plenoptic
  location <0, 0.5, -2> look_at <0, 0.3, 0>
  main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }
  sensor { pixel_size 0.02 }
  samples 4"""
PERSPECTIVE = "perspective location <0, 0.5, -2> look_at <0, 0.3, 0>"


def test_antialias_warning(args):
    # pt.render passes -A; a later +A on the command line wins (POV-Ray reads options in order).
    plain = pt.render(args.povray, args.work, "plain", SCENE % PLENOPTIC, 80, 60)
    rc, text = pt.render(args.povray, args.work, "antialiased", SCENE % PLENOPTIC, 80, 60,
                             extra=["+A0.1", "+AM2", "+R3"], expect_failure=True)
    assert rc == 0, "render with +A succeeds" + ": " + ("exit %d" % rc)
    text = " ".join(text.split())  # POV-Ray wraps its messages
    count = text.count(WARNING)
    assert count == 1, "one warning" + ": " + ("'%s' printed %d time(s)" % (WARNING, count))
    assert "samples" in text[text.find(WARNING):text.find(WARNING) + 200], "the warning names samples" + ": " + (text[text.find(WARNING) - 20:text.find(WARNING) + 120].strip())
    if rc == 0:
        a = pt.load(plain)
        b = pt.load(plain.replace("plain", "antialiased"))
        assert np.array_equal(a, b), "+A changes nothing in the image" + ": " + ("largest difference %g" % float(np.abs(a - b).max()))
    rc, text = pt.render(args.povray, args.work, "perspective", SCENE % PERSPECTIVE, 80, 60,
                             extra=["+A0.1"], expect_failure=True)
    text = " ".join(text.split())
    assert (rc == 0 and WARNING not in text), "no warning for a stock camera" + ": " + ("exit %d, warning %s" % (rc, "printed" if WARNING in text else "absent"))

