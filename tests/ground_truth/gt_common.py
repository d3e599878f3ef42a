# SPDX-License-Identifier: AGPL-3.0-or-later
"""Shared helpers of the ground-truth tests: rendering, reading outputs, checks, and the optics
of the specification (docs/specification.md, docs/metadata.md) written
out again here, independently of the code under test."""

import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np


# --------------------------------------------------------------------------------------------
# Command line, rendering

def parse_args(description):
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--povray", required=True, help="the povray binary under test")
    parser.add_argument("--project", required=True, help="the plenoptic-project binary")
    parser.add_argument("--tools", required=True, help="the tools/ folder (the plenoptic-decode launcher)")
    parser.add_argument("--python", default=None,
                        help="the folder holding the plenoptic_lf package (default: python/ beside --tools)")
    parser.add_argument("--work", required=True, help="scratch folder for renders")
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    if args.python is None:
        args.python = os.path.join(os.path.dirname(os.path.abspath(args.tools)), "python")
    sys.path.insert(0, os.path.abspath(args.python))
    return args


SCENE_HEADER = """#version 3.7;
global_settings { assumed_gamma 1.0 }
"""


def render(args, name, scene, width, height, extra=()):
    """Renders `scene` (text, header added) as <work>/<name>.png, 16-bit linear (File_Gamma 1).
    Returns the paths of the image, the metadata and the depth map."""
    pov = os.path.join(args.work, name + ".pov")
    png = os.path.join(args.work, name + ".png")
    for stale in (png, os.path.join(args.work, name + ".plenoptic.json"), os.path.join(args.work, name + ".depth.exr")):
        if os.path.exists(stale):
            os.remove(stale)
    with open(pov, "w") as f:
        f.write(SCENE_HEADER + scene)
    cmd = [args.povray, "+I" + name + ".pov", "+O" + name + ".png", "+W%d" % width, "+H%d" % height,
           "-D", "-P", "+FN16", "File_Gamma=1.0"] + list(extra)
    start = time.monotonic()
    run = subprocess.run(cmd, cwd=args.work, capture_output=True, text=True)
    elapsed = time.monotonic() - start
    if run.returncode != 0:
        sys.stderr.write(run.stderr[-3000:])
        raise SystemExit("FAIL: rendering %s exited with status %d" % (name, run.returncode))
    print("rendered %s (%d x %d) in %.1f s" % (name, width, height, elapsed))
    return png, os.path.join(args.work, name + ".plenoptic.json"), os.path.join(args.work, name + ".depth.exr")


def read_linear(png):
    """16-bit linear PNG -> float (H, W, 3) in [0, 1]."""
    import OpenImageIO as oiio
    buf = oiio.ImageBuf(png)
    if buf.has_error:
        raise SystemExit("FAIL: cannot read %s: %s" % (png, buf.geterror()))
    data = np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float64)
    return data[:, :, :3]


def read_json(path):
    """A JSON file; a render's metadata (*.plenoptic.json) is read strictly and checked against
    docs/metadata.schema.json (tests/metadata/metadata_schema.py)."""
    if path.endswith(".plenoptic.json"):
        shared = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "metadata")
        if shared not in sys.path:
            sys.path.insert(0, shared)
        import metadata_schema
        try:
            return metadata_schema.load(path)
        except metadata_schema.MetadataError as e:
            raise SystemExit("FAIL: %s" % e)
    with open(path) as f:
        return json.load(f)


# --------------------------------------------------------------------------------------------
# Checks

class Checks:
    """Collects failures; every check prints what it measured and what it expected."""

    def __init__(self, name):
        self.name = name
        self.failures = []
        self.start = time.monotonic()

    def check(self, ok, message):
        print(("ok    " if ok else "FAIL  ") + message)
        if not ok:
            self.failures.append(message)
        return ok

    def finish(self):
        print("%s: %.1f s" % (self.name, time.monotonic() - self.start))
        if self.failures:
            print("%s: %d check(s) failed:" % (self.name, len(self.failures)))
            for f in self.failures:
                print("  - " + f)
            sys.exit(1)
        print("%s: all checks passed" % self.name)
        sys.exit(0)


# --------------------------------------------------------------------------------------------
# The optics of docs/specification.md, written out again

def image_distance(F, z):
    """Thin lens: where an object at distance z (same unit as F, z > F) is imaged behind the lens."""
    return z * F / (z - F)


def lens_centre_local(grid, pitch, k, l):
    """Lens (k, l) in row form, in the array's own plane (docs/specification.md, section 2)."""
    k = np.asarray(k, float)
    l = np.asarray(l, float)
    if grid == "hexagonal":
        return np.stack([(k + np.mod(l, 2) / 2.0) * pitch, l * pitch * math.sqrt(3) / 2.0], axis=-1)
    return np.stack([k * pitch, l * pitch], axis=-1)


def nearest_lens_local(grid, pitch, xy):
    """Row-form index of the lens whose centre is nearest each point (array-local mm), by brute
    force over the candidates around it; also the gap between the best and second-best squared
    distance (small: the point is near a cell border). xy: (..., 2)."""
    xy = np.asarray(xy, float)
    row = pitch * (math.sqrt(3) / 2.0 if grid == "hexagonal" else 1.0)
    l0 = np.floor(xy[..., 1] / row)
    best_d = np.full(xy.shape[:-1], np.inf)
    second_d = np.full(xy.shape[:-1], np.inf)
    best_k = np.zeros(xy.shape[:-1])
    best_l = np.zeros(xy.shape[:-1])
    for dl in (-1, 0, 1, 2):
        l = l0 + dl
        shift = np.mod(l, 2) / 2.0 if grid == "hexagonal" else 0.0
        k0 = np.floor(xy[..., 0] / pitch - shift)
        for dk in (-1, 0, 1, 2):
            k = k0 + dk
            c = lens_centre_local(grid, pitch, k, l)
            d = ((xy - c) ** 2).sum(axis=-1)
            better = d < best_d
            second_d = np.where(better, best_d, np.minimum(second_d, d))
            best_k = np.where(better, k, best_k)
            best_l = np.where(better, l, best_l)
            best_d = np.where(better, d, best_d)
    return best_k, best_l, second_d - best_d


def rot_z(degrees):
    a = math.radians(degrees)
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def sensor_point(i, j, W, H, sx, sy, ox=0.0, oy=0.0):
    """Sensor position (mm, optics frame) of the centre of pixel (column i, row j):
    docs/specification.md, section 2, with (i + 0.5) the centre of a pixel spanning [i, i + 1)."""
    return -((np.asarray(i, float) + 0.5) - W / 2.0) * sx + ox, ((np.asarray(j, float) + 0.5) - H / 2.0) * sy + oy


def sensor_to_pixel(x, y, W, H, sx, sy, ox=0.0, oy=0.0):
    """Inverse of sensor_point in the metadata's convention (pixel centre at (i, j))."""
    return W / 2.0 - 0.5 - (np.asarray(x) - ox) / sx, H / 2.0 - 0.5 + (np.asarray(y) - oy) / sy


# --------------------------------------------------------------------------------------------
# Blobs

def blobs(image, threshold):
    """Connected components (8-neighbourhood) of pixels brighter than threshold in a grey image.
    Returns a list of dicts: centroid (u, v) weighted by brightness (pixel (i, j) centre at (i, j)),
    flux (sum), count, bbox."""
    mask = image > threshold
    labels = np.zeros(image.shape, np.int32)
    H, W = image.shape
    found = []
    for j0, i0 in zip(*np.nonzero(mask)):
        if labels[j0, i0]:
            continue
        label = len(found) + 1
        stack = [(j0, i0)]
        labels[j0, i0] = label
        pixels = []
        while stack:
            j, i = stack.pop()
            pixels.append((j, i))
            for dj in (-1, 0, 1):
                for di in (-1, 0, 1):
                    jj, ii = j + dj, i + di
                    if 0 <= jj < H and 0 <= ii < W and mask[jj, ii] and not labels[jj, ii]:
                        labels[jj, ii] = label
                        stack.append((jj, ii))
        js = np.array([p[0] for p in pixels])
        is_ = np.array([p[1] for p in pixels])
        w = image[js, is_]
        flux = w.sum()
        found.append({"u": float((w * is_).sum() / flux), "v": float((w * js).sum() / flux), "flux": float(flux),
                      "count": len(pixels), "bbox": (int(is_.min()), int(js.min()), int(is_.max()), int(js.max()))})
    return found


def run_project(args, metadata, points):
    """plenoptic-project on world points: list of (point, k, l, u, v)."""
    cmd = [args.project, metadata] + ["%.17g" % c for p in points for c in p]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        raise SystemExit("FAIL: plenoptic-project exited %d: %s" % (run.returncode, run.stderr.strip()))
    hits = []
    for line in run.stdout.splitlines():
        i, k, l, u, v = line.split()
        hits.append((int(i), int(k), int(l), float(u), float(v)))
    return hits
