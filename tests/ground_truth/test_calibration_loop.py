# SPDX-License-Identifier: AGPL-3.0-or-later
"""The calibration loop (docs/calibration-loop.md): tools/calibration-loop renders seven of the
R12-A checkerboard poses through a plenoptic 1.0 camera behind the wide-angle lens of lenses/
(Laikin's 22 mm, strong barrel distortion), decodes the central views, and OpenCV
(cv2.findChessboardCorners, cv2.calibrateCamera) calibrates them. What it recovers must be the
central view's camera as the optics gives it, worked out here with the tests' own tracer
(plenoptic_testing.lens_tracer), not with the tool's code:

  - the central view has one pixel per lens of the rectangular array (pitch p); its pixel (s, t)
    sees along the chief ray from that lens's centre through the exit pupil's centre, D' in front
    of the array; an object-side angle theta from the entrance pupil leaves the exit pupil at
    tan(theta) / m (m the pupils' magnification), so f = D' / (m p) view pixels;
  - the principal point is the lens on the axis: the sensor's centre is a lens centre (even
    raw size, lens (0, 0) on the axis) and the decoder keeps as many lenses on each side, so it is
    the view's centre;
  - the radial distortion: the real chief rays, traced from lens centres on the array through the
    exit pupil's centre out of the lens (apertures lifted), meet the plane at the focus at angles
    theta from the entrance pupil's centre; OpenCV's model r_d = r_u (1 + k1 r_u^2 + k2 r_u^4)
    with r_u = tan(theta) and r_d = c m / D' (c the lens centre's height), fitted over the
    calibrated field.

Tolerances (docs/calibration-loop.md, "Agreement"): fx and fy within 2 %, the principal point
within 3 view pixels, k1 within 0.03 and the distortion at the farthest corner within 0.5
percentage points (of about -6 %). A model without the pupils' magnification (2.07), with D
from the rear vertex instead of the exit pupil, or without distortion fails them.
"""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt

LENS = os.path.join(pt.SOURCE_DIR, "lenses", "wide_angle_22mm_laikin_f3.5.dat")
F_NUMBER, FOCUS_MM = 4.0, 650.0
LENSES = 100
FRAMES = "5,0,9,15,12,10,8"


@pytest.fixture(scope="module")
def loop(args):
    pytest.importorskip("cv2", reason="OpenCV's Python module (Debian: python3-opencv), tools/lib/packages")
    out = os.path.join(args.work, "calibration_loop")
    cmd = [sys.executable, os.path.join(args.tools, "calibration-loop"), "--out", out, "--lenses", str(LENSES),
           "--samples", "4", "--frames", FRAMES, "--povray", args.povray, "--project", args.project]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=1500)
    assert run.returncode == 0, run.stderr[-4000:]
    print(run.stderr[-1500:])
    with open(os.path.join(out, "calibration.json")) as f:
        return out, json.load(f)


def lifted_apertures(lens):
    """The lens with every clear aperture opened as wide as its sphere allows (chief rays)."""
    rows = [s._replace(aperture=200.0) if s.is_stop else s._replace(aperture=min(200.0, 1.999 * abs(s.radius)))
            for s in lens.surfaces]
    return lt.Lens(rows, stop_diameter=200.0)


def optics():
    rows = lt.parse_lens_file(open(LENS).read())
    full = lt.Lens(rows)
    lens = lt.Lens(rows, stop_diameter=full.stop_diameter * lt.paraxial_data(full).f_number / F_NUMBER)
    p = lt.paraxial_data(lens)
    D = lt.paraxial_image_distance(lens, FOCUS_MM)
    return lens, p, D


def test_calibration_recovers_the_central_view_camera(loop):
    out, report = loop
    lens, par, D = optics()
    L = lens.length
    Dp = D + (L - par.exit_pupil_z)
    m = par.exit_pupil_diameter / par.entrance_pupil_diameter
    meta = pt.load_metadata(os.path.join(out, "targets", "target_000.plenoptic.json"))
    assert meta["main_lens"]["type"] == "prescription"
    assert abs(meta["main_lens"]["distance_mm"] - D) < 1e-6 * D
    assert meta["microlens_array"]["grid"] == "rectangular"
    p = meta["microlens_array"]["pitch_mm"]
    f_view = Dp / (m * p)
    view_w, view_h = report["view_size"]
    rec, exp = report["recovered"], report["expected"]

    # The distortion of the real chief rays over the calibrated field.
    r_max = exp["r_max"]
    c = np.linspace(0.02, 1.0, 40) * r_max * Dp / m  # lens-centre heights on the array, mm
    lifted = lifted_apertures(lens)
    origins = np.column_stack([c, np.zeros_like(c), np.full(len(c), L + D)])
    target = np.array([0.0, 0.0, par.exit_pupil_z])
    traced = lt.trace_image_to_object(lifted, origins, target - origins)
    assert traced.passed.all()
    q, dirs = traced.points, traced.directions
    t = (-FOCUS_MM - q[:, 2]) / dirs[:, 2]
    height = np.hypot(q[:, 0] + t * dirs[:, 0], q[:, 1] + t * dirs[:, 1])
    r_u = height / (FOCUS_MM + par.entrance_pupil_z)
    r_d = c * m / Dp
    k1, k2 = np.linalg.lstsq(np.column_stack([r_u ** 3, r_u ** 5]), r_d - r_u, rcond=None)[0]
    # The distortion at the farthest corner, as a function of the undistorted radius there.
    ru_max = np.interp(r_max, r_d, r_u)
    dist_traced = k1 * ru_max ** 2 + k2 * ru_max ** 4
    dist_rec = rec["k1"] * ru_max ** 2 + rec["k2"] * ru_max ** 4

    print("calibration loop: %d of %d views used, rms %.3f px; view %d x %d" % (
        len(report["views_used"]), len(report["views"]), rec["rms_px"], view_w, view_h))
    print("  fx %.3f fy %.3f (optics %.3f; metadata %.3f), cx %.3f cy %.3f (optics %.1f %.1f), OpenCV's sd: %s" % (
        rec["fx"], rec["fy"], f_view, exp["fx"], rec["cx"], rec["cy"], (view_w - 1) / 2, (view_h - 1) / 2, rec["sd"]))
    print("  k1 %.4f k2 %.4f (traced %.4f %.4f; metadata's profile %.4f %.4f); distortion at r %.3f: %.2f %% recovered, "
          "%.2f %% traced" % (rec["k1"], rec["k2"], k1, k2, exp["k1"], exp["k2"], ru_max, 100 * dist_rec, 100 * dist_traced))

    # The corners were found in most views, and fit the model to a fraction of a view pixel.
    assert len(report["views_used"]) >= 5, report["views"]
    assert rec["rms_px"] < 0.5, rec["rms_px"]
    # The metadata's implication (the tool's) is the optics (the test's).
    assert abs(exp["fx"] / f_view - 1) < 1e-6 and abs(exp["fy"] / f_view - 1) < 1e-6, (exp["fx"], f_view)
    assert abs(exp["cx"] - (view_w - 1) / 2) < 1e-9 and abs(exp["cy"] - (view_h - 1) / 2) < 1e-9
    assert abs(exp["k1"] - k1) < 0.01, (exp["k1"], k1)
    # The distortion is visible: at the farthest corner it moves points by several view pixels.
    assert dist_traced < -0.03 and abs(dist_traced) * r_max * f_view > 1.5, dist_traced
    # The calibration recovers it.
    for key in ("fx", "fy"):
        assert abs(rec[key] / f_view - 1) < 0.02, (key, rec[key], f_view)
    assert abs(rec["cx"] - (view_w - 1) / 2) < 3 and abs(rec["cy"] - (view_h - 1) / 2) < 3, (rec["cx"], rec["cy"])
    assert abs(rec["k1"] - k1) < 0.03, (rec["k1"], k1)
    assert abs(dist_rec - dist_traced) < 0.005, (dist_rec, dist_traced)
    assert os.path.getsize(os.path.join(out, "corners.png")) > 1000
