# SPDX-License-Identifier: AGPL-3.0-or-later
"""calibration-loop: a standard calibration (OpenCV) run on our renders recovers the camera our
metadata describes (docs/calibration-loop.md).

    calibration-loop --out DIR [--lenses N] [--samples S] [--views K,K,...] [--lens FILE]
                     [--povray PATH] [--project PATH]

1. Writes DIR/camera.inc: a plenoptic 1.0 camera behind a real lens with visible barrel
   distortion (lenses/wide_angle_22mm_laikin_f3.5.dat at f/4, focused at 0.65 m; a rectangular
   array of N x 3N/4 microlenses, microimages of about 6 pixels, d matched to the lens's working
   f-number; a 20.4 x 15.3 mm sensor).
2. Renders the R12-A checkerboard set through it with plenoptic-targets (R12A_POSES: the poses of
   the data set R12-A as COMPOTE's calibration of it estimated them, scaled to this camera's
   field; the 9 x 5 board of 10 mm squares scaled with them).
3. Decodes every raw (the package's decoder) and takes the central view (one pixel per lens).
4. Finds the inner corners with OpenCV (cv2.findChessboardCorners on the view enlarged 4 times,
   cv2.cornerSubPix), calibrates (cv2.calibrateCamera: fx, fy, cx, cy, k1, k2; no tangential
   distortion, k3 = 0).
5. Works out what the metadata implies for the central view (expected_intrinsics) and writes
   DIR/calibration.json (recovered, expected, their differences) and DIR/corners.png (the
   detected corners on one central view).

Needs OpenCV's Python module (Debian: python3-opencv).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from typing import Any, Sequence

import numpy as np

from .errors import DependencyError
from .locate import REPOSITORY

# The poses of the data set R12-A (a Raytrix R12 focused at h = 450 mm, a 9 x 5 checkerboard of
# 10 mm squares), as the calibration shipped with COMPOTE estimated them (comsee-research/compote,
# examples/config/poses.js, 15 frames): per frame, the board's rotation as POV-Ray's
# rotate <rx, ry, rz> (degrees; x, then y, then z) and its centre (mm) in the camera's frame
# (x right, y up, z along the view). Derived from the file's rotation R and translation t: the
# board's origin (a corner) lies at -R t, its centre at R (45, 25, 0) - R t, with y turned from
# the file's downward y to our upward one. Tilts from 1 to 55 degrees, distances 239 to 363 mm.
R12A_POSES = (  # frame, rx, ry, rz, x, y, z
    (5, 0.2, -4.8, -1.2, -13.7, -9.6, 270.8),
    (3, 16.9, 26.0, 2.9, -25.7, -9.2, 327.0),
    (2, 1.2, -54.6, 0.7, -6.1, 1.9, 294.4),
    (0, -1.3, -3.3, -0.5, -9.7, 2.4, 362.6),
    (1, -2.5, 37.6, -6.3, -13.0, -6.9, 249.8),
    (6, -1.7, -42.5, 1.2, -6.3, -11.0, 309.7),
    (7, -0.5, -4.0, -1.3, -5.0, -3.0, 292.8),
    (8, -0.8, -3.6, -0.4, -11.7, 1.9, 336.3),
    (9, -0.8, -11.2, -25.6, -5.8, -5.8, 328.2),
    (14, -0.6, -1.1, -0.4, -28.4, 2.2, 337.6),
    (15, -0.2, -4.2, -1.8, -8.3, 1.1, 238.8),
    (13, -1.0, -6.0, -0.5, -11.8, 1.9, 336.9),
    (12, 35.2, -30.6, -23.7, 4.2, -0.4, 261.0),
    (11, -18.7, -28.9, 9.2, 6.2, -1.3, 325.5),
    (10, -0.5, 17.2, -3.6, -14.9, -6.3, 277.2),
)
R12A_SQUARE_MM = 10.0
R12A_BOARD = (5, 9)  # rows, columns of squares
# The R12's half field across (sensor half-width 11.22 mm at D = 56.86 mm) against this camera's
# (a 10.2 mm half-width behind the 22 mm lens: tan of its paraxial half field, 10.2 / 22.0):
# the board and its distances are scaled so that it spans the same fraction of the view.
R12_HALF_FIELD_TAN = 11.22 / 56.86
SQUARE_M = 0.05  # the scaled board's squares (m)

LENS = "wide_angle_22mm_laikin_f3.5.dat"
F_NUMBER = 4.0
FOCUS_M = 0.65
SENSOR_WIDTH_MM = 20.4  # 4 : 3
MICROIMAGE_PX = 6
WORKING_F_NUMBER = 4.05  # the lens's at f/4 near this focus: d = 4.05 p (about f-number matched)
UPSCALE = 4


def camera_text(lenses: int, samples: int, lens: str = LENS) -> str:
    """The calibration camera with `lenses` microlenses across (view width), 3/4 as many down."""
    width = MICROIMAGE_PX * lenses
    pixel = SENSOR_WIDTH_MM / width
    pitch = MICROIMAGE_PX * pixel
    d = WORKING_F_NUMBER * pitch
    return ("// SPDX-License-Identifier: AGPL-3.0-or-later\n// Written by calibration-loop (docs/calibration-loop.md).\n"
            "// Render at +W%d +H%d.\n"
            "camera { plenoptic\n"
            "  mm_per_unit 1000\n"
            "  main_lens { lens_file \"%s\" f_number %r focus_distance %r }\n"
            "  microlens_array { rectangular pitch %.17g focal_length %.17g distance %.17g }\n"
            "  sensor { pixel_size %.17g }\n"
            "  samples %d\n"
            "}\n" % (width, width * 3 // 4, lens, F_NUMBER, FOCUS_M, pitch, d, d, pixel, samples))


def scaled_poses(frames: Sequence[int] | None = None) -> tuple[list[dict[str, Any]], float]:
    """R12A_POSES in metres for this camera's board (SQUARE_M), and the scale applied to
    distances: the square's over R12-A's, times the ratio of the two cameras' half fields."""
    tan_here = (SENSOR_WIDTH_MM / 2) / 22.0
    scale = SQUARE_M / (R12A_SQUARE_MM / 1000.0) * R12_HALF_FIELD_TAN / tan_here
    poses: list[dict[str, Any]] = []
    for frame, rx, ry, rz, x, y, z in R12A_POSES:
        if frames is not None and frame not in frames:
            continue
        poses.append({"rotate_deg": [rx, ry, rz], "translate": [x / 1000 * scale, y / 1000 * scale, z / 1000 * scale],
                      "r12a_frame": frame})
    return poses, scale


def expected_intrinsics(meta_json: dict[str, Any], lattice: dict[str, Any], width: int, height: int,
                        r_max: float) -> dict[str, Any]:
    """The central view's pinhole camera as the metadata implies it, in view pixels (OpenCV's
    convention: pixel centres at integers).

    The central view's pixel (s, t) is the lens whose microimage centre is the raw position
    origin + (s0 + s) A + (t0 + t) R (the decoder's grid); it sees along the chief ray from the
    lens centre through the exit pupil's centre, D' = D + exit_pupil_z in front of the array.
    Lens centres are the microimage centres scaled by D' / (D' + d) about the axis; an object-side
    chief ray at angle theta from the entrance pupil leaves the exit pupil at tan(theta) / m, m
    the pupils' magnification (exit over entrance pupil diameter). So
        f = D' / (m |A|_mm)   with |A|_mm = |A| s D' / (D' + d): f = (D' + d) / (m |A| s),
    the principal point is the grid position of the axis (the sensor's centre), and the radial
    distortion is the profile's real over paraxial height, fitted with OpenCV's
    r_d = r_u (1 + k1 r_u^2 + k2 r_u^4), r_u = paraxial and r_d = real height over D' / m, up to
    r_d = r_max (the farthest corner's normalised radius as the view shows it), and evaluated
    there: distortion_at_r_max is k1 r_u^2 + k2 r_u^4 at the r_u that images at r_max."""
    lens = meta_json["main_lens"]
    par = lens["paraxial"]
    s_x, s_y = meta_json["sensor"]["pixel_size_mm"]
    d = meta_json["microlens_array"]["distance_mm"]
    Dp = lens["distance_mm"] + par["exit_pupil_z_mm"]
    m = par["exit_pupil_diameter_mm"] / par["entrance_pupil_diameter_mm"]
    A = np.array(lattice["A"], float)
    R = np.array(lattice["R"], float)
    fx = (Dp + d) / (m * abs(A[0]) * s_x)
    fy = (Dp + d) / (m * abs(R[1]) * s_y)
    origin = np.array(lattice["origin"], float)
    s0, t0 = lattice["origin_st"]
    axis = np.array(meta_json["principal_point_px"], float)  # where the axis meets the sensor
    st = np.linalg.solve(np.column_stack([A, R]), axis - origin)
    cx, cy = st[0] - s0, st[1] - t0
    rows = [r for r in lens["distortion_profile"]["samples"] if r[2] > 0]
    ru = np.array([r[2] for r in rows]) * m / Dp
    rd = np.array([r[3] for r in rows]) * m / Dp
    keep = rd <= r_max * 1.0001
    keep[min(int(keep.sum()), len(keep) - 1)] = True  # and the next row beyond, so that r_max is inside
    X = np.column_stack([ru[keep] ** 3, ru[keep] ** 5])
    k1, k2 = np.linalg.lstsq(X, rd[keep] - ru[keep], rcond=None)[0]
    ru_max = float(np.interp(r_max, rd, ru))
    return {"fx": fx, "fy": fy, "cx": float(cx), "cy": float(cy), "k1": float(k1), "k2": float(k2),
            "exit_pupil_to_array_mm": Dp, "pupil_magnification": m, "profile_rows_fitted": int(keep.sum()),
            "r_max": r_max, "r_u_at_r_max": ru_max, "distortion_at_r_max": float(k1 * ru_max ** 2 + k2 * ru_max ** 4)}


def undistorted_radius(k1: float, k2: float, r_d: float) -> float:
    """The r_u with r_u (1 + k1 r_u^2 + k2 r_u^4) = r_d (bisection on [0, 2 r_d]; the model is
    monotonic there for the lenses the loop uses)."""
    lo, hi = 0.0, 2.0 * r_d
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if mid * (1 + k1 * mid ** 2 + k2 * mid ** 4) < r_d:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _cv2() -> Any:
    try:
        import cv2
    except ImportError:
        raise DependencyError("calibration-loop needs OpenCV's Python module (Debian: apt install python3-opencv)")
    return cv2


def central_view(png: str) -> tuple[np.ndarray, dict[str, Any], dict[str, Any], int, int]:
    """(grey central view, metadata JSON, the decoder's grid, width, height) of one raw."""
    from .focus import gray
    from .images import read_raw
    from .lightfield import decode
    from .metadata import load_metadata
    raw = read_raw(png)
    height, width = raw.shape[:2]
    stem = os.path.splitext(png)[0]
    meta = load_metadata(stem + ".plenoptic.json", (width, height))
    lf = decode(raw, meta)
    iv, iu = lf.centre_index()
    assert lf.du[iu] == 0 and lf.dv[iv] == 0
    view = gray(lf.view(iv, iu)).astype(np.float64)
    with open(stem + ".plenoptic.json") as f:
        meta_json = json.load(f)
    grid = {"A": [float(v) for v in lf.A], "R": [float(v) for v in lf.R],
            "origin": [float(v) for v in meta.origin], "origin_st": [int(v) for v in lf.origin_st]}
    return view, meta_json, grid, width, height


def find_corners(view: np.ndarray, pattern: tuple[int, int]) -> np.ndarray | None:
    """The inner corners (cols-1 x rows-1) in view pixels (N, 2), or None when OpenCV finds none.
    The view is enlarged UPSCALE times (cubic) for the detector, and the corners refined there."""
    cv2 = _cv2()
    image = np.clip(view / max(float(np.percentile(view, 99.5)), 1e-12) * 255, 0, 255).astype(np.uint8)
    big = cv2.resize(image, None, fx=UPSCALE, fy=UPSCALE, interpolation=cv2.INTER_CUBIC)
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(big, pattern, flags=flags)
    if not found:
        return None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-4)
    corners = cv2.cornerSubPix(big, corners, (2 * UPSCALE + 1, 2 * UPSCALE + 1), (-1, -1), criteria)
    return (corners.reshape(-1, 2).astype(np.float64) + 0.5) / UPSCALE - 0.5


def board_points(rows: int, cols: int, square: float) -> np.ndarray:
    """The inner corners in the board's frame, in OpenCV's order for a pattern (cols-1, rows-1):
    row by row; which corner comes first is OpenCV's choice, and the calibration does not care
    as long as the grid is the board's (a square board would be ambiguous; 9 x 5 is not)."""
    pts = [((i - cols / 2.0) * square, (j - rows / 2.0) * square, 0.0)
           for j in range(1, rows) for i in range(1, cols)]
    return np.array(pts, np.float32)


def calibrate(views: list[np.ndarray], corner_sets: list[np.ndarray], rows: int, cols: int,
              square: float) -> dict[str, Any]:
    cv2 = _cv2()
    h, w = views[0].shape
    obj = [board_points(rows, cols, square) for _ in corner_sets]
    img = [c.astype(np.float32).reshape(-1, 1, 2) for c in corner_sets]
    flags = cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K3
    rms, K, dist, rvecs, tvecs, sd, _, _ = cv2.calibrateCameraExtended(obj, img, (w, h), None, None, flags=flags)
    sd = sd.ravel()  # fx, fy, cx, cy, k1, k2, p1, p2, k3, ...: OpenCV's standard deviations
    return {"fx": float(K[0, 0]), "fy": float(K[1, 1]), "cx": float(K[0, 2]), "cy": float(K[1, 2]),
            "k1": float(dist.ravel()[0]), "k2": float(dist.ravel()[1]), "rms_px": float(rms),
            "sd": {key: float(sd[i]) for i, key in enumerate(("fx", "fy", "cx", "cy", "k1", "k2"))},
            "distances_m": [float(np.linalg.norm(t)) for t in tvecs]}


def corners_picture(path: str, view: np.ndarray, corners: np.ndarray, pattern: tuple[int, int]) -> None:
    cv2 = _cv2()
    image = np.clip(view / max(float(np.percentile(view, 99.5)), 1e-12) * 255, 0, 255).astype(np.uint8)
    big = cv2.cvtColor(cv2.resize(image, None, fx=UPSCALE, fy=UPSCALE, interpolation=cv2.INTER_NEAREST),
                       cv2.COLOR_GRAY2BGR)
    at = ((corners + 0.5) * UPSCALE - 0.5).astype(np.float32).reshape(-1, 1, 2)
    cv2.drawChessboardCorners(big, pattern, at, True)
    cv2.imwrite(path, big)


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="calibration-loop", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--lenses", type=int, default=200,
                   help="microlenses across (the central view's width; 3/4 as many down; default 200, "
                        "a raw of 1200 x 900 pixels)")
    p.add_argument("--samples", type=int, default=16, help="camera samples per pixel (default 16)")
    p.add_argument("--frames", default=None, metavar="K,K,...",
                   help="R12-A frames to render (default: all 15)")
    p.add_argument("--povray", default=None)
    p.add_argument("--project", default=None)
    args = p.parse_args(argv)

    def fail(message: str) -> int:
        print("calibration-loop: error: %s" % message, file=sys.stderr)
        return 2

    try:
        _cv2()
    except DependencyError as e:
        return fail(str(e))
    if not 20 <= args.lenses <= 2000 or args.samples < 1:
        return fail("--lenses must lie in 20 .. 2000 and --samples be at least 1")
    frames = None
    if args.frames:
        try:
            frames = [int(v) for v in args.frames.split(",")]
        except ValueError:
            return fail("--frames: a comma-separated list of R12-A frame numbers, not %r" % args.frames)
        unknown = sorted(set(frames) - {row[0] for row in R12A_POSES})
        if unknown:
            return fail("--frames: R12-A has frames %s, not %s" % (
                ", ".join(str(r[0]) for r in sorted(R12A_POSES)), ", ".join(map(str, unknown))))
    os.makedirs(args.out, exist_ok=True)
    width = MICROIMAGE_PX * args.lenses
    height = width * 3 // 4
    camera = os.path.join(args.out, "camera.inc")
    with open(camera, "w") as f:
        f.write(camera_text(args.lenses, args.samples))
    poses, scale = scaled_poses(frames)
    poses_path = os.path.join(args.out, "poses.json")
    with open(poses_path, "w") as f:
        json.dump(poses, f, indent=1)
    rows, cols = R12A_BOARD
    square = SQUARE_M
    from . import targets
    targets_dir = os.path.join(args.out, "targets")
    cmd = ["--out", targets_dir, "--poses", poses_path, "--target", "checkerboard:%dx%d:%r" % (rows, cols, square),
           "--width", str(width), "--height", str(height)]
    if args.povray:
        cmd += ["--povray", args.povray]
    if args.project:
        cmd += ["--project", args.project]
    cmd.append(camera)
    lenses_dir = os.path.join(REPOSITORY, "lenses")
    if os.path.isdir(lenses_dir):  # the source tree's catalogue (an installed POV-Ray finds its own)
        cmd += ["--", "+L" + lenses_dir]
    status = targets.main(cmd)
    if status != 0:
        return fail("plenoptic-targets failed (status %d)" % status)
    pattern = (cols - 1, rows - 1)
    views, corner_sets, used, records = [], [], [], []
    meta_json: dict[str, Any] = {}
    grid: dict[str, Any] = {}
    for k, pose in enumerate(poses):
        png = os.path.join(targets_dir, "target_%03d.png" % k)
        view, meta_json, grid, w, h = central_view(png)
        corners = find_corners(view, pattern)
        records.append({"view": k, "r12a_frame": pose["r12a_frame"], "corners_found": corners is not None})
        print("calibration-loop: view %d (R12-A frame %d): %s" % (k, pose["r12a_frame"],
              "%d corners" % len(corners) if corners is not None else "no checkerboard found"), file=sys.stderr)
        if corners is not None:
            views.append(view)
            corner_sets.append(corners)
            used.append(k)
    if len(corner_sets) < 3:
        return fail("OpenCV found the checkerboard in only %d views: at least 3 are needed" % len(corner_sets))
    recovered = calibrate(views, corner_sets, rows, cols, square)
    vh, vw = views[0].shape
    # The normalised radius of the farthest corner used: the distortion fit's range.
    K = np.array([[recovered["fx"], 0, recovered["cx"]], [0, recovered["fy"], recovered["cy"]]])
    r_max = max(float(np.max(np.hypot((c[:, 0] - K[0, 2]) / K[0, 0], (c[:, 1] - K[1, 2]) / K[1, 1])))
                for c in corner_sets)
    expected = expected_intrinsics(meta_json, grid, w, h, r_max)
    ru_max = undistorted_radius(recovered["k1"], recovered["k2"], r_max)
    recovered["r_u_at_r_max"] = ru_max
    recovered["distortion_at_r_max"] = recovered["k1"] * ru_max ** 2 + recovered["k2"] * ru_max ** 4
    difference = {"fx_percent": 100 * (recovered["fx"] / expected["fx"] - 1),
                  "fy_percent": 100 * (recovered["fy"] / expected["fy"] - 1),
                  "cx_px": recovered["cx"] - expected["cx"], "cy_px": recovered["cy"] - expected["cy"],
                  "k1": recovered["k1"] - expected["k1"],
                  "distortion_at_r_max_percent_points": 100 * (recovered["distortion_at_r_max"] -
                                                               expected["distortion_at_r_max"])}
    corners_picture(os.path.join(args.out, "corners.png"), views[0], corner_sets[0], pattern)
    report = {"camera": os.path.abspath(camera), "raw_size": [w, h], "view_size": [vw, vh],
              "board": {"rows": rows, "cols": cols, "square_m": square}, "pose_scale": scale,
              "views": records, "views_used": used, "recovered": recovered, "expected": expected,
              "difference": difference}
    with open(os.path.join(args.out, "calibration.json"), "w") as f:
        json.dump(report, f, indent=1)
    print("calibration-loop: %d of %d views; rms %.3f px" % (len(used), len(poses), recovered["rms_px"]), file=sys.stderr)
    for key in ("fx", "fy", "cx", "cy", "k1", "k2", "distortion_at_r_max"):
        print("  %-20s recovered %10.5f   expected %10.5f" % (key, recovered[key], expected[key]), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
