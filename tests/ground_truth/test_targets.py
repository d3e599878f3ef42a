# SPDX-License-Identifier: AGPL-3.0-or-later
"""Calibration targets with ground truth (docs/ground-truth.md, "Calibration
targets"): plenoptic-targets renders a checkerboard or a circle grid (scenes/calibration_targets.inc)
at seeded random poses and writes where every feature point images.

Checked against answers that are not the tool's:
  - behind a pinhole without an array (POV-Ray's perspective camera), each corner's pixel is the
    pinhole projection written out here, u = W/2 - 1/2 + D X / (Z s), v = H/2 - 1/2 - D Y / (Z s),
    and the rendered image shows a checkerboard corner there: the two diagonal pairs of pixels
    around it are each of one colour, and the two colours differ;
  - the poses lie in the ranges asked for, the same seed gives the same data set, another seed
    another one;
  - behind a plenoptic camera the corners, out of focus, have several images each, all inside the picture.
"""
import csv
import json
import os
import subprocess
import sys

import numpy as np

import plenoptic_testing as pt

W, H = 320, 240
PINHOLE = "camera { plenoptic main_lens { pinhole distance 20 } sensor { pixel_size 0.01 } }\n"
PLENOPTIC = ("camera { plenoptic main_lens { thin_lens focal_length 20 f_number 4 focus_distance 1 }\n"
             "  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 } sensor { pixel_size 0.01 } samples 4 }\n")


def run_tool(args, name, camera, extra):
    work = os.path.join(args.work, name)
    os.makedirs(work, exist_ok=True)
    cam = pt.write_text(os.path.join(work, "camera.inc"), camera)
    out = os.path.join(work, "out")
    cmd = [sys.executable, os.path.join(args.tools, "plenoptic-targets"), cam, "--out", out,
           "--width", str(W), "--height", str(H), "--povray", args.povray, "--project", args.project] + extra
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    with open(os.path.join(out, "targets.json")) as f:
        return out, json.load(f)


def rows_of(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def check_pinhole_views(out, data, rows_n, cols_n, square, camera_rotate=(0, 0, 0), camera_location=(0, 0, 0)):
    """Every corner of every view where the pinhole of PINHOLE (rotated by camera_rotate, then
    moved to camera_location, as the camera file says) projects it, and a corner rendered there."""
    D, s = 20.0, 0.01
    C, c0 = pt.rotation_xyz(camera_rotate), np.array(camera_location, dtype=float)

    def pixel(world_m):
        X, Y, Z = (c * 1000 for c in C.T @ (world_m - c0))  # the camera's frame, mm
        return W / 2 - 0.5 + D * X / (Z * s), H / 2 - 0.5 - D * Y / (Z * s)

    for view in data["views"]:
        pose = view["pose"]
        assert 0.9 <= pose["translate"][2] <= 1.2
        assert all(abs(t) <= 30 for t in pose["rotate_deg"][:2])
        # The pose is relative to the camera: carried into the world by the camera's placement.
        R, t = C @ pt.rotation_xyz(pose["rotate_deg"]), C @ np.array(pose["translate"]) + c0
        rows = rows_of(os.path.join(out, view["points"]))
        assert len(rows) == view["feature_points"] == (rows_n - 1) * (cols_n - 1)  # one image each
        image = pt.read_linear(os.path.join(out, view["image"]))[..., 1]
        checked = 0
        for r in rows:
            # The corner from its row and column, as calibration_targets.inc places it, posed here.
            local = np.array([(int(r["col"]) + 1 - cols_n / 2.0) * square, (int(r["row"]) + 1 - rows_n / 2.0) * square, 0])
            world = R @ local + t
            assert np.abs(world - [float(r[k]) for k in ("x", "y", "z")]).max() < 1e-12 * (1 + np.abs(c0).max()), r
            u, v = pixel(world)
            assert abs(float(r["u"]) - u) < 1e-6 and abs(float(r["v"]) - v) < 1e-6, r
            # The render: the centres of the four squares around the corner, a pair of each colour.
            centres = [pixel(R @ (local + square * 0.3 * np.array([a, b, 0])) + t) for a, b in ((-1, -1), (1, 1), (1, -1), (-1, 1))]
            if not all(1 <= cu < W - 1 and 1 <= cv < H - 1 for cu, cv in centres):
                continue
            values = [image[int(round(cv)), int(round(cu))] for cu, cv in centres]
            assert abs(values[0] - values[1]) < 0.1 and abs(values[2] - values[3]) < 0.1 and \
                abs(values[0] - values[2]) > 0.5, (r, values)
            checked += 1
        assert checked >= 12, checked


def test_pinhole_corners_are_where_the_pinhole_projects_them_and_the_render_shows_corners(args):
    rows_n, cols_n, square = 5, 7, 0.012
    out, data = run_tool(args, "pinhole", PINHOLE, ["--count", "3", "--seed", "5", "--distance", "0.9", "1.2",
                                                    "--tilt", "30", "--target", "checkerboard:%dx%d:%r" % (rows_n, cols_n, square)])
    check_pinhole_views(out, data, rows_n, cols_n, square)


def test_a_placed_camera_gets_targets_posed_relative_to_it(args):
    # The camera file places the camera itself: turned 70 degrees about y (to look along +x
    # mostly), tilted 10 degrees about x, moved off the origin.
    rotate, location = (10, 70, 0), (0.3, -0.2, 0.5)
    camera = PINHOLE.replace("sensor { pixel_size 0.01 }", "sensor { pixel_size 0.01 } rotate <%r, %r, %r> "
                             "translate <%r, %r, %r>" % (rotate + location))
    rows_n, cols_n, square = 5, 7, 0.012
    out, data = run_tool(args, "placed", camera, ["--count", "2", "--seed", "5", "--distance", "0.9", "1.2",
                                                  "--tilt", "30", "--target", "checkerboard:%dx%d:%r" % (rows_n, cols_n, square)])
    check_pinhole_views(out, data, rows_n, cols_n, square, rotate, location)
    placement = data["camera_placement"]
    C = pt.rotation_xyz(rotate)
    assert np.abs(np.array(placement["location"]) - location).max() < 1e-9, placement
    assert np.abs(np.array(placement["direction"]) - C[:, 2]).max() < 1e-9, placement


def test_a_camera_that_is_not_plenoptic_is_named_so(args):
    work = os.path.join(args.work, "not_plenoptic")
    os.makedirs(work, exist_ok=True)
    out = os.path.join(work, "out")
    for name, camera in (("perspective", "camera { perspective location <0, 0, 0> look_at <0, 0, 1> }\n"),
                         ("none", "// no camera: POV-Ray's default perspective camera\n")):
        cam = pt.write_text(os.path.join(work, name + ".inc"), camera)
        cmd = [sys.executable, os.path.join(args.tools, "plenoptic-targets"), cam, "--out", out, "--count", "1",
               "--width", "32", "--height", "24", "--povray", args.povray, "--project", args.project]
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        line = run.stderr.strip()
        assert run.returncode == 2 and "not plenoptic" in line and name + ".inc" in line and "\n" not in line, line
        assert not [n for n in os.listdir(out) if n.startswith("target_")], "no view left: %s" % os.listdir(out)


def test_seeds_decide_the_data_set(args):
    extra = ["--count", "2", "--distance", "0.9", "1.2", "--target", "circles:3x4:0.02:0.005"]
    _, one = run_tool(args, "seed_a", PINHOLE, extra + ["--seed", "7"])
    _, same = run_tool(args, "seed_b", PINHOLE, extra + ["--seed", "7"])
    _, other = run_tool(args, "seed_c", PINHOLE, extra + ["--seed", "8"])
    assert [v["pose"] for v in one["views"]] == [v["pose"] for v in same["views"]]
    assert [v["pose"] for v in one["views"]] != [v["pose"] for v in other["views"]]
    assert one["views"][0]["feature_points"] == 12


def test_plenoptic_camera_images_each_corner_several_times(args):
    # Nearer than the focus (1 m): a point focused on the array lights one lens; out of focus, several.
    out, data = run_tool(args, "plenoptic", PLENOPTIC, ["--count", "1", "--seed", "2", "--distance", "0.5", "0.6",
                                                        "--target", "checkerboard:4x5:0.008"])
    rows = rows_of(os.path.join(out, data["views"][0]["points"]))
    per_point = {}
    for r in rows:
        assert -0.5 <= float(r["u"]) < W - 0.5 and -0.5 <= float(r["v"]) < H - 0.5
        per_point.setdefault(r["point"], []).append(r)
    print("plenoptic: %d corners, %d images (%.1f each)" % (len(per_point), len(rows), len(rows) / len(per_point)))
    assert len(per_point) == 3 * 4
    # Near the picture's edge some images fall outside it; most corners keep several.
    assert sum(len(v) >= 2 for v in per_point.values()) >= 0.75 * len(per_point)
    assert len(rows) >= 2 * len(per_point)
