# SPDX-License-Identifier: AGPL-3.0-or-later
"""Pinhole main lens, no array == POV-Ray's stock perspective camera.

docs/specification.md, section 3: a pinhole at distance D from a sensor of W x H pixels of size sx
is the perspective camera with `angle 2 atan(W sx / 2D)` and `right x*W/H up y`: the
same pixels. For each case both cameras render the same textured scene (16-bit linear
PNG, one ray per pixel) and must agree exactly; OpenImageIO's idiff is asked the same
question with a zero tolerance.

Derivation used for the cases docs/specification.md does not spell out (non-square pixels and
a sensor offset): with right R, up U (|U| = 1) and direction L (perpendicular), stock
POV-Ray shoots pixel (i, j) along L + ((i+.5)/W - .5) R + (.5 - (j+.5)/H) U. The
plenoptic pinhole shoots from the sensor point x = -((i+.5) - W/2) sx + ox,
y = ((j+.5) - H/2) sy + oy through the pinhole, i.e. along (-x, -y, D) in camera
coordinates. Equal directions need |R| = W sx / (H sy), |L| = D / (H sy) and, for an
offset, a direction vector tilted by (-ox, -oy) / (H sy) in right/up units.
"""
import math
import shutil
import os

import numpy as np
import pytest

import plenoptic_testing as pt

LOCATION = (0.15, 0.7, -3.0)
LOOK_AT = (0.0, 0.45, 0.0)

# (name, W, H, sx, sy, D, ox, oy): sizes in pixels, lengths in mm
CASES = [
    ("square_4x3", 160, 120, 0.01, 0.01, 2.4, 0.0, 0.0),
    ("portrait", 90, 150, 0.02, 0.02, 2.5, 0.0, 0.0),
    ("wide_2x1", 200, 100, 0.006, 0.006, 1.6, 0.0, 0.0),
    ("odd_size", 101, 77, 0.013, 0.013, 1.9, 0.0, 0.0),
    ("nonsquare_pixels", 120, 90, 0.012, 0.008, 2.0, 0.0, 0.0),
    ("sensor_offset", 128, 96, 0.01, 0.01, 1.8, 0.15, -0.08),
]


def vec(a):
    return "<%.17g, %.17g, %.17g>" % tuple(a)


def frame_vectors():
    """The frame look_at gives a camera: z towards the target, x = sky x z, y = z x x."""
    loc, tgt = np.array(LOCATION), np.array(LOOK_AT)
    z = (tgt - loc) / np.linalg.norm(tgt - loc)
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    return loc, x, np.cross(z, x), z


def stock_camera(W, H, sx, sy, D, ox, oy):
    if ox == 0 and oy == 0 and sx == sy:
        # The form of docs/specification.md (section 3), verbatim.
        angle = 2 * math.degrees(math.atan(W * sx / (2 * D)))
        return ("camera { perspective location %s look_at %s right x*%r/%r up y angle %.17g }"
                % (vec(LOCATION), vec(LOOK_AT), float(W), float(H), angle))
    unit = H * sy  # one `up` unit, in mm on the sensor
    if ox == 0 and oy == 0:
        # Non-square pixels: |right| = W sx / (H sy), |direction| = D / (H sy); look_at
        # keeps these lengths while it turns the frame.
        return ("camera { perspective location %s right x*%.17g up y direction z*%.17g look_at %s }"
                % (vec(LOCATION), W * sx / unit, D / unit, vec(LOOK_AT)))
    # Offset: a direction tilted by (-ox, -oy) / (H sy); look_at would re-aim it, so the
    # frame is given explicitly, built as look_at builds the plenoptic camera's.
    loc, x, y, z = frame_vectors()
    return ("camera { perspective location %s right %s up %s direction %s }"
            % (vec(loc), vec(x * (W * sx / unit)), vec(y), vec(z * (D / unit) - x * (ox / unit) - y * (oy / unit))))


@pytest.mark.parametrize("name, W, H, sx, sy, D, ox, oy", CASES, ids=[c[0] for c in CASES])
def test_pinhole_vs_perspective(args, name, W, H, sx, sy, D, ox, oy):
    idiff = shutil.which("idiff")
    stock = stock_camera(W, H, sx, sy, D, ox, oy)
    plen = ("camera { plenoptic location %s look_at %s\n"
            "  main_lens { pinhole distance %r }\n"
            "  sensor { pixel_size <%r, %r> offset <%r, %r> } }" % (vec(LOCATION), vec(LOOK_AT), D, sx, sy, ox, oy))
    a = pt.render(args.povray, args.work, name + "_stock", pt.TEXTURED_SCENE + stock, W, H)
    b = pt.render(args.povray, args.work, name + "_plenoptic", pt.TEXTURED_SCENE + plen, W, H)
    ia, ib = pt.load(a), pt.load(b)
    diff = np.abs(ia - ib).max(axis=2)
    n_diff = int((diff > 0).sum())
    where = ""
    if n_diff:
        j, i = np.unravel_index(np.argmax(diff), diff.shape)
        where = "; largest at pixel (%d, %d): stock %s plenoptic %s" % (
            i, j, np.round(ia[j, i], 4).tolist(), np.round(ib[j, i], 4).tolist())
        pt.save_png(os.path.join(args.work, name + "_diff.png"), np.minimum(1, 16 * diff))
    assert (n_diff == 0), (name + ": " + ("%dx%d sx=%g sy=%g D=%g offset=(%g, %g): %d of %d pixels differ, max |diff| %.3g (expected 0)%s"
                 % (W, H, sx, sy, D, ox, oy, n_diff, W * H, float(diff.max()), where)))
    assert idiff, name + " (idiff): OpenImageIO's idiff is not installed"
    code, report = pt.idiff(a, b, ["-fail", "0", "-failpercent", "0", "-hardfail", "0"])
    out = report.splitlines()
    assert code == 0, name + " (idiff): " + ("idiff exit %d (0 = identical): %s" % (code, out[-1] if out else ""))

