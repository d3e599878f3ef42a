# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-targets: calibration data sets with ground truth (docs/ground-truth.md,
"Calibration targets").

Renders N views of a calibration target (scenes/calibration_targets.inc: a checkerboard or a
circle grid) at seeded random poses in front of a camera, and writes for each view every feature
point's 3-D position and every raw pixel where it images (the forward projection,
plenoptic-project):

    plenoptic-targets CAMERA.inc --out DIR [--count N] [--seed S] [--distance MIN MAX]
                      [--tilt DEG] [--target checkerboard:ROWSxCOLS:SQUARE | circles:ROWSxCOLS:SPACING:RADIUS]
                      [--width W --height H] [--povray PATH] [--project PATH] [-- POVRAY OPTIONS]
    plenoptic-targets CAMERA.inc --out DIR --poses POSES.json [--target ...] ...

CAMERA.inc holds the camera, `camera { plenoptic ... }`, placed anywhere (location, look_at,
transforms). A pose is relative to the camera, in its frame (x right, y up, z the viewing
direction, from its `location`): a distance z drawn uniformly from [MIN, MAX] (scene units) along
the viewing direction, an offset across of up to --lateral times z, tilts about x and y drawn
uniformly from [-DEG, DEG] and a roll about z from [-180, 180); the target is rotated (x, then
y, then z, POV-Ray's order), then moved, then carried into the world by the camera's placement,
which the first view's metadata gives (when the camera is not at POV-Ray's default placement,
the first view is rendered again, placed). A camera that is not plenoptic is refused.
--poses POSES.json gives the poses instead of the draw: a JSON list of {"rotate_deg": [rx, ry, rz],
"translate": [x, y, z]} in the same frame and units (the calibration loop gives the R12-A data
set's, calibration.py).

For view k, DIR holds target_<k>.png (and what the camera writes beside it: the metadata, white
image, raw...), target_<k>.pov, and target_<k>.points.csv: one line per image of a feature point,
    point, row, col, x, y, z, lens_k, lens_l, u, v
(point index, its row and column on the target, its world position in scene units, the lens of
the image in row form and its pixel position, pixel centres at integers). DIR/targets.json lists
the views with their poses and the command line.
"""

import argparse
import json
import math
import os
import random
import subprocess
import sys
from typing import Sequence

import numpy as np

from .errors import DependencyError, MetadataError
from .locate import PREFIX, REPOSITORY, find_povray, find_project
from .metadata import REAL_LENS_TYPES, RenderMetadata, read_metadata
from .povray import povray_command, run_povray


def rotation_xyz(degrees):
    """POV-Ray's `rotate <rx, ry, rz>` as a matrix acting on column vectors: x first, then y, then
    z, each the textbook rotation matrix (POV-Ray's Compute_Rotation_Transform, which applies their
    transposes to row vectors)."""
    ax, ay, az = (math.radians(d) for d in degrees)
    rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
    ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
    rz = np.array([[math.cos(az), -math.sin(az), 0], [math.sin(az), math.cos(az), 0], [0, 0, 1]])
    return rz @ ry @ rx


def parse_target(text):
    """'checkerboard:7x10:0.03' or 'circles:4x11:0.02:0.006' -> dict."""
    parts = text.split(":")
    try:
        rows, cols = (int(v) for v in parts[1].lower().split("x"))
        numbers = [float(v) for v in parts[2:]]
    except (IndexError, ValueError):
        raise ValueError("--target: checkerboard:ROWSxCOLS:SQUARE or circles:ROWSxCOLS:SPACING:RADIUS, not %r" % text)
    if parts[0] == "checkerboard" and len(numbers) == 1 and rows >= 2 and cols >= 2 and numbers[0] > 0:
        return {"kind": "checkerboard", "rows": rows, "cols": cols, "square": numbers[0]}
    if parts[0] == "circles" and len(numbers) == 2 and rows >= 1 and cols >= 1 and numbers[0] > 0 and \
            0 < numbers[1] < numbers[0] / 2:
        return {"kind": "circles", "rows": rows, "cols": cols, "spacing": numbers[0], "radius": numbers[1]}
    raise ValueError("--target: checkerboard:ROWSxCOLS:SQUARE (rows, cols >= 2, square > 0) or "
                     "circles:ROWSxCOLS:SPACING:RADIUS (0 < radius < spacing / 2), not %r" % text)


def feature_points(target):
    """[(row, col, (x, y, 0))] in the target's frame, as calibration_targets.inc documents them."""
    out = []
    if target["kind"] == "checkerboard":
        rows, cols, s = target["rows"], target["cols"], target["square"]
        for j in range(1, rows):
            for i in range(1, cols):
                out.append((j - 1, i - 1, ((i - cols / 2.0) * s, (j - rows / 2.0) * s, 0.0)))
    else:
        rows, cols, s = target["rows"], target["cols"], target["spacing"]
        for j in range(rows):
            for i in range(cols):
                out.append((j, i, ((i - (cols - 1) / 2.0) * s, (j - (rows - 1) / 2.0) * s, 0.0)))
    return out


def target_object(target):
    if target["kind"] == "checkerboard":
        return "Plenoptic_Checkerboard(%d, %d, %.17g, rgb 0.9, rgb 0.05)" % (target["rows"], target["cols"], target["square"])
    return "Plenoptic_Circle_Grid(%d, %d, %.17g, %.17g, rgb 0.9, rgb 0.05)" % (
        target["rows"], target["cols"], target["spacing"], target["radius"])


def draw_pose(rng, distance, tilt, lateral):
    z = rng.uniform(distance[0], distance[1])
    return {"rotate_deg": [rng.uniform(-tilt, tilt), rng.uniform(-tilt, tilt), rng.uniform(-180.0, 180.0)],
            "translate": [rng.uniform(-lateral, lateral) * z, rng.uniform(-lateral, lateral) * z, z]}


def read_poses(path):
    """--poses: a non-empty JSON list of {"rotate_deg": [3 numbers], "translate": [3 numbers]},
    the translation's z > 0 (in front of the camera). ValueError naming the file and the pose."""
    with open(path) as f:
        try:
            data = json.load(f)
        except json.JSONDecodeError as e:
            raise ValueError("%s: not JSON (%s)" % (path, e))
    if not isinstance(data, list) or not data:
        raise ValueError("%s: a non-empty JSON list of poses is needed" % path)
    poses = []
    for k, pose in enumerate(data):
        try:
            r = [float(v) for v in pose["rotate_deg"]]
            t = [float(v) for v in pose["translate"]]
        except (TypeError, KeyError, ValueError):
            raise ValueError("%s: pose %d: needs rotate_deg and translate, three numbers each" % (path, k))
        if len(r) != 3 or len(t) != 3 or not all(math.isfinite(v) for v in r + t) or t[2] <= 0:
            raise ValueError("%s: pose %d: rotate_deg and translate must be three finite numbers each, translate's "
                             "z > 0 (in front of the camera), not %r, %r" % (path, k, r, t))
        poses.append({"rotate_deg": r, "translate": t})
    return poses


def posed_points(target, pose):
    """[(row, col, point)]: the feature points posed, in the camera's frame."""
    r = rotation_xyz(pose["rotate_deg"])
    t = np.array(pose["translate"])
    return [(row, col, r @ np.array(p) + t) for row, col, p in feature_points(target)]


# POV-Ray's default camera placement: at the origin, x right, y up, looking along +z.
DEFAULT_PLACEMENT = {"location": [0.0, 0.0, 0.0], "right": [1.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
                     "direction": [0.0, 0.0, 1.0]}


def camera_placement(meta: RenderMetadata) -> dict[str, list[float]]:
    """The camera's placement in the world from its metadata: its `location` (the main-lens centre;
    a real lens's front vertex, front_vertex_z_mm ahead of the optics frame's origin, the rear
    vertex, along the viewing direction) and the unit vectors right, up and direction. The
    default placement exactly when it is that within 1e-12."""
    frame = meta.camera_frame
    location = np.array(frame.location, dtype=float)
    direction = np.array(frame.direction, dtype=float)
    if meta.main_lens.type in REAL_LENS_TYPES:
        location = location + meta.main_lens.front_vertex_z_mm / meta.mm_per_unit * direction
    placement = {"location": location.tolist(), "right": [float(v) for v in frame.right],
                 "up": [float(v) for v in frame.up], "direction": direction.tolist()}
    if all(abs(a - b) <= 1e-12 for key in DEFAULT_PLACEMENT for a, b in zip(placement[key], DEFAULT_PLACEMENT[key])):
        return dict(DEFAULT_PLACEMENT)
    return placement


def to_world(placement, point):
    """A point of the camera's frame (x right, y up, z the viewing direction, from its location)
    in the world."""
    return (np.array(placement["location"]) + point[0] * np.array(placement["right"]) +
            point[1] * np.array(placement["up"]) + point[2] * np.array(placement["direction"]))


def scene_text(camera_path, target, pose, placement=DEFAULT_PLACEMENT):
    place = ""
    if placement != DEFAULT_PLACEMENT:  # POV-Ray's matrix: the images of x, y, z, then the translation
        place = " matrix <%s>" % ", ".join("%.17g" % v for key in ("right", "up", "direction", "location")
                                           for v in placement[key])
    return ("// SPDX-License-Identifier: AGPL-3.0-or-later\n// Written by plenoptic-targets.\n#version 3.7;\n"
            "global_settings { assumed_gamma 1.0 }\nbackground { rgb 0.2 }\n#include \"calibration_targets.inc\"\n"
            "#include \"%s\"\nobject { %s rotate <%.17g, %.17g, %.17g> translate <%.17g, %.17g, %.17g>%s }\n"
            % (os.path.abspath(camera_path), target_object(target), *pose["rotate_deg"], *pose["translate"], place))




def _include_dir():
    """The folder holding calibration_targets.inc: the source tree's scenes/ or the install's."""
    for c in (os.path.join(REPOSITORY, "scenes"), os.path.join(PREFIX, "share", "povray-plenoptic", "scenes")):
        if os.path.exists(os.path.join(c, "calibration_targets.inc")):
            return os.path.abspath(c)
    raise FileNotFoundError("calibration_targets.inc not found beside the plenoptic_lf package")


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="plenoptic-targets", description=__doc__.split("\n\n")[0])
    p.add_argument("camera", help="a file holding camera { plenoptic ... } (the poses are relative to it)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--count", type=int, default=10)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--distance", type=float, nargs=2, default=[0.8, 1.5], metavar=("MIN", "MAX"),
                   help="distance range along the optical axis, scene units (default 0.8 1.5)")
    p.add_argument("--tilt", type=float, default=30.0, help="largest tilt about x and y, degrees (default 30)")
    p.add_argument("--lateral", type=float, default=0.02,
                   help="largest offset across the axis, as a fraction of the distance (default 0.02)")
    p.add_argument("--target", default="checkerboard:7x10:0.03")
    p.add_argument("--poses", default=None, metavar="JSON",
                   help="the poses, a JSON list of {rotate_deg: [3], translate: [3]}, instead of the seeded draw")
    p.add_argument("--width", type=int, default=640)
    p.add_argument("--height", type=int, default=480)
    p.add_argument("--povray", default=None)
    p.add_argument("--project", default=None)
    p.add_argument("povray_options", nargs="*", help="after --: passed to POV-Ray (e.g. +WT2)")
    args = p.parse_args(argv)

    def fail(message):
        print("plenoptic-targets: error: %s" % message, file=sys.stderr)
        return 2

    try:
        target = parse_target(args.target)
    except ValueError as e:
        return fail(str(e))
    if not os.path.isfile(args.camera):
        return fail("%s: no such camera file" % args.camera)
    if not (args.count >= 1 and 0 < args.distance[0] <= args.distance[1] and 0 <= args.tilt < 90 and
            args.lateral >= 0 and args.width >= 1 and args.height >= 1):
        return fail("need --count >= 1, 0 < MIN <= MAX, 0 <= --tilt < 90, --lateral >= 0 and a positive size")
    try:
        povray = find_povray(args.povray)
        project = find_project(args.project)
        include = _include_dir()
    except FileNotFoundError as e:
        return fail(str(e))
    if args.poses is not None:
        try:
            poses = read_poses(args.poses)
        except (OSError, ValueError) as e:
            return fail(str(e))
        args.count = len(poses)
    else:
        rng = random.Random(args.seed)
        poses = [draw_pose(rng, args.distance, args.tilt, args.lateral) for _ in range(args.count)]
    os.makedirs(args.out, exist_ok=True)
    views = []
    placement = None  # the camera's, from the first view's metadata
    try:
        k = 0
        while k < args.count:
            pose = poses[k]
            name = "target_%03d" % k
            pov = os.path.join(args.out, name + ".pov")
            with open(pov, "w") as f:
                f.write(scene_text(args.camera, target, pose, placement or DEFAULT_PLACEMENT))
            png = os.path.join(args.out, name + ".png")
            meta = os.path.join(args.out, name + ".plenoptic.json")
            if os.path.exists(meta):  # an earlier run's: the render below must write its own
                os.remove(meta)
            cmd = povray_command(povray, pov, png, args.width, args.height,
                                 ["-D", "-P", "+L" + include, "+FN16", "File_Gamma=1.0"] + list(args.povray_options))
            run = run_povray(cmd, separate=True)
            if run.returncode != 0 or not os.path.exists(png):
                return fail("the render of view %d failed (%s):\n%s" % (k, " ".join(cmd), (run.stderr or "")[-2000:]))
            if not os.path.exists(meta):
                for leftover in os.listdir(args.out):
                    if leftover.startswith(name + "."):
                        os.remove(os.path.join(args.out, leftover))
                return fail("%s: the camera is not plenoptic (POV-Ray wrote no plenoptic metadata): plenoptic-targets "
                            "needs a file holding camera { plenoptic ... }" % args.camera)
            if placement is None:
                try:
                    placement = camera_placement(read_metadata(meta))
                except (MetadataError, DependencyError) as e:
                    return fail("%s: cannot read the camera's placement (camera_frame): %s" % (meta, e))
                if placement != DEFAULT_PLACEMENT:
                    print("plenoptic-targets: the camera is placed at <%s>, looking along <%s>: the targets are posed "
                          "relative to it (view 0 rendered again)" % (", ".join("%.6g" % v for v in placement["location"]),
                                                                       ", ".join("%.6g" % v for v in placement["direction"])),
                          file=sys.stderr)
                    continue
            points = [(row, col, to_world(placement, p)) for row, col, p in posed_points(target, pose)]
            stdin = "".join("%.17g %.17g %.17g\n" % tuple(p) for _, _, p in points)
            proj = subprocess.run([project, meta, "-"], input=stdin, capture_output=True, text=True)
            if proj.returncode != 0:
                return fail("plenoptic-project failed on view %d:\n%s" % (k, proj.stderr[-2000:]))
            images = 0
            with open(os.path.join(args.out, name + ".points.csv"), "w") as f:
                f.write("point,row,col,x,y,z,lens_k,lens_l,u,v\n")
                for line in proj.stdout.splitlines():
                    index, lk, ll, u, v = line.split()[:5]
                    row, col, p3 = points[int(index)]
                    f.write("%s,%d,%d,%.17g,%.17g,%.17g,%s,%s,%s,%s\n" % (index, row, col, p3[0], p3[1], p3[2], lk, ll, u, v))
                    images += 1
            views.append({"view": k, "image": name + ".png", "points": name + ".points.csv", "pose": pose,
                          "feature_points": len(points), "images_of_points": images})
            print("plenoptic-targets: view %d of %d: %d feature points, %d images of them"
                  % (k + 1, args.count, len(points), images), file=sys.stderr)
            k += 1
    except KeyboardInterrupt:
        print("plenoptic-targets: interrupted after %d views" % len(views), file=sys.stderr)
        return 130
    finally:
        if views:  # the views made (all of them, or those before a failure or an interruption)
            with open(os.path.join(args.out, "targets.json"), "w") as f:
                record = {"target": target, "seed": args.seed, "distance": args.distance, "tilt_deg": args.tilt,
                          "lateral": args.lateral, "size": [args.width, args.height],
                          "camera": os.path.abspath(args.camera), "camera_placement": placement, "views": views}
                if args.poses is not None:  # the poses were given, not drawn
                    record["poses_file"] = os.path.abspath(args.poses)
                json.dump(record, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
