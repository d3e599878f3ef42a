# SPDX-License-Identifier: AGPL-3.0-or-later
"""Shared helpers of the camera render tests (tests/camera/).

Everything the tests expect is computed here or in the test itself from the
specification (docs/specification.md, docs/camera.md), never by
calling the camera code: the renders are the only thing the code under test
produces.
"""
import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio


# ---------------------------------------------------------------- rendering

class RenderError(RuntimeError):
    pass


def common_args(description):
    """Argument parser shared by every test script."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--povray", required=True, help="the povray binary under test")
    ap.add_argument("--work", required=True, help="scratch directory (created)")
    return ap


def render(povray, work, name, scene, width, height, ext="png", extra=(), expect_failure=False):
    """Write `scene` (text) to <work>/<name>.pov and render it to <work>/<name>.<ext>.

    PNG outputs are 16-bit and linear (File_Gamma=1.0), EXR outputs are half-float
    linear: both give values proportional to the traced radiance. Returns the path of
    the image, or (exit code, console text) when expect_failure is set.
    """
    os.makedirs(work, exist_ok=True)
    pov = os.path.join(work, name + ".pov")
    out = os.path.join(work, name + "." + ext)
    with open(pov, "w") as f:
        f.write(scene)
    for stale in (out, os.path.join(work, name + ".plenoptic.json")):
        if os.path.exists(stale):
            os.remove(stale)
    fmt = {"png": ["+FN16", "File_Gamma=1.0"], "exr": ["+FE"]}[ext]
    cmd = [povray, "+I" + pov, "+O" + out, "+W%d" % width, "+H%d" % height,
           "-D", "-P", "-A", "-V", "-GR", "-GS"] + fmt + list(extra)
    res = subprocess.run(cmd, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         timeout=300)
    text = res.stdout.decode(errors="replace")
    if expect_failure:
        return res.returncode, text
    animated = any(a.startswith("+KFF") for a in extra)  # frames are <name><number>.<ext>
    if res.returncode != 0 or not (animated or os.path.exists(out)):
        raise RenderError("render of %s failed (exit %d): %s\n%s" %
                          (pov, res.returncode, " ".join(cmd), text[-3000:]))
    return out


def load(path):
    """Image as float32 array [row, column, channel] (values as stored, 0..1 for PNG)."""
    buf = oiio.ImageBuf(path)
    pixels = buf.get_pixels(oiio.FLOAT)
    if pixels is None or buf.has_error:
        raise RenderError("cannot read %s: %s" % (path, buf.geterror()))
    return np.asarray(pixels, dtype=np.float64)


def metadata(image_path):
    """The render's metadata, read strictly and checked against docs/metadata.schema.json
    (tests/metadata/metadata_schema.py); a MetadataError (ValueError) when it does not match."""
    shared = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "metadata")
    if shared not in sys.path:
        sys.path.insert(0, shared)
    import metadata_schema
    stem = os.path.splitext(image_path)[0]
    return metadata_schema.load(stem + ".plenoptic.json")


def save_png(path, array):
    """Write a float image (H, W[, C]) in 0..1 as an 8-bit PNG, for a person to look at."""
    a = np.clip(np.asarray(array, dtype=np.float64), 0, 1)
    if a.ndim == 2:
        a = a[:, :, None]
    spec = oiio.ImageSpec(a.shape[1], a.shape[0], a.shape[2], oiio.UINT8)
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(0, a.shape[1], 0, a.shape[0], 0, 1, 0, a.shape[2]),
                   (a * 255 + 0.5).astype(np.uint8))
    buf.write(path)


# ---------------------------------------------------------------- reporting

class Checks:
    """Collects named checks; each prints PASS/FAIL with measured and expected values."""

    def __init__(self, title):
        self.title = title
        self.failures = []
        print("== " + title)

    def check(self, ok, name, detail):
        print("%s %s: %s" % ("PASS" if ok else "FAIL", name, detail))
        sys.stdout.flush()
        if not ok:
            self.failures.append(name)
        return ok

    def finish(self):
        if self.failures:
            print("%d check(s) failed in %s: %s" % (len(self.failures), self.title,
                                                    ", ".join(self.failures)))
            return 1
        print("all checks passed in %s" % self.title)
        return 0


# ---------------------------------------------------------------- geometry (docs/specification.md)

SQRT3 = math.sqrt(3.0)


def rotation_xyz(deg):
    """Rotate about x, then y, then z (POV-Ray's order), degrees; column-vector matrix."""
    ax, ay, az = [math.radians(a) for a in deg]
    cx, sx = math.cos(ax), math.sin(ax)
    cy, sy = math.cos(ay), math.sin(ay)
    cz, sz = math.cos(az), math.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def lattice_point(grid, pitch, k, l):
    """Lens centre in the array's own plane (docs/specification.md, section 2), row-form indices."""
    if grid == "hexagonal":
        return np.array([(k + (l % 2) / 2.0) * pitch, l * pitch * SQRT3 / 2.0, 0.0])
    return np.array([k * pitch, l * pitch, 0.0])


def posed_lens_centre(grid, pitch, k, l, rotate, translate, D):
    """Optics-frame centre of lens (k, l): rotate, translate, then place at z = -D."""
    q = rotation_xyz(rotate) @ lattice_point(grid, pitch, k, l)
    return q + np.array(translate, dtype=float) + np.array([0.0, 0.0, -D])


def sensor_to_pixel(x, y, W, H, sx, sy, ox=0.0, oy=0.0):
    """Sensor point (optics frame, mm) -> continuous pixel coordinates with the centre of
    pixel (i, j) at (i, j) (docs/specification.md, section 2: x = -((i + 0.5) - W/2) sx + ox ...)."""
    u = W / 2.0 - 0.5 - (x - ox) / sx
    v = H / 2.0 - 0.5 + (y - oy) / sy
    return u, v


def thin_lens_D(F, z_mm):
    """Image distance of a thin lens focused at z (1/F = 1/z + 1/D)."""
    return 1.0 / (1.0 / F - 1.0 / z_mm)


# ---------------------------------------------------------------- image measurements

def label_components(mask):
    """4-connected components of a boolean mask: (labels array, count). Labels 1..count."""
    H, W = mask.shape
    labels = np.zeros((H, W), dtype=np.int32)
    count = 0
    for j0 in range(H):
        for i0 in range(W):
            if not mask[j0, i0] or labels[j0, i0]:
                continue
            count += 1
            stack = [(j0, i0)]
            labels[j0, i0] = count
            while stack:
                j, i = stack.pop()
                for jj, ii in ((j - 1, i), (j + 1, i), (j, i - 1), (j, i + 1)):
                    if 0 <= jj < H and 0 <= ii < W and mask[jj, ii] and not labels[jj, ii]:
                        labels[jj, ii] = count
                        stack.append((jj, ii))
    return labels, count


def dilate(mask, radius):
    """Binary dilation by a (2 radius + 1)^2 square: joins stray lit pixels at the ragged,
    sampled edge of a microimage to its body before labelling."""
    m = np.asarray(mask, dtype=bool)
    out = m.copy()
    H, W = m.shape
    for dj in range(-radius, radius + 1):
        for di in range(-radius, radius + 1):
            src = m[max(0, -dj):H - max(0, dj), max(0, -di):W - max(0, di)]
            out[max(0, dj):H - max(0, -dj), max(0, di):W - max(0, -di)] |= src
    return out


def component_centroids(weight, labels, count):
    """Weighted centroid (u, v) (pixel-centre convention), weight sum, bounding box and
    pixel count of every component."""
    H, W = weight.shape
    vv, uu = np.mgrid[0:H, 0:W]
    out = []
    for c in range(1, count + 1):
        sel = labels == c
        w = weight[sel]
        s = w.sum()
        if s <= 0:
            continue
        out.append({
            "u": float((uu[sel] * w).sum() / s),
            "v": float((vv[sel] * w).sum() / s),
            "weight": float(s),
            "umin": int(uu[sel].min()), "umax": int(uu[sel].max()),
            "vmin": int(vv[sel].min()), "vmax": int(vv[sel].max()),
            "pixels": int(sel.sum()),
        })
    return out


def box_blur(img, k):
    """Mean over k x k neighbourhoods ('valid' region only), any number of channels."""
    a = np.asarray(img, dtype=np.float64)
    c = np.cumsum(np.cumsum(a, axis=0), axis=1)
    c = np.pad(c, ((1, 0), (1, 0)) + ((0, 0),) * (a.ndim - 2))
    s = c[k:, k:] - c[:-k, k:] - c[k:, :-k] + c[:-k, :-k]
    return s / (k * k)


# ---------------------------------------------------------------- scenes

# A textured 3-D scene in metres (one unit = 1 m = 1000 mm, the camera's default scale):
# a checkered floor, a marbled sphere, a striped box and a wall with a fine grid, at depths
# from 1.5 to 6 m in front of a camera at z = -3 looking along +z. No randomness (no area
# lights, no jitter, no radiosity), so every camera sees exactly the same surfaces.
TEXTURED_SCENE = """
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "colors.inc"
light_source { <-3, 6, -6> rgb 1.0 }
light_source { <4, 3, -5> rgb 0.35 shadowless }
background { rgb <0.45, 0.6, 0.85> }
plane { y, 0
  pigment { checker rgb <0.9, 0.85, 0.7> rgb <0.15, 0.2, 0.25> scale 0.25 }
  finish { diffuse 0.8 ambient 0.1 } }
sphere { <-0.45, 0.4, -1.2>, 0.4
  pigment { marble turbulence 0.8 color_map { [0 rgb <0.9, 0.2, 0.1>] [0.5 rgb <1, 0.9, 0.5>] [1 rgb <0.3, 0.05, 0.1>] } scale 0.15 }
  finish { specular 0.4 roughness 0.02 ambient 0.1 } }
box { <-0.25, 0, -0.25>, <0.25, 0.9, 0.25> rotate y*30 translate <0.55, 0, 0.2>
  pigment { gradient x color_map { [0 rgb <0.1, 0.3, 0.9>] [0.5 rgb <0.1, 0.3, 0.9>] [0.5 rgb 1] [1 rgb 1] } scale 0.08 }
  finish { ambient 0.1 } }
cylinder { <0, 0, 0>, <0, 1.4, 0>, 0.12 translate <-0.1, 0, 1.4>
  pigment { radial frequency 12 color_map { [0 rgb <0.1, 0.6, 0.2>] [0.5 rgb <0.1, 0.6, 0.2>] [0.5 rgb <0.9, 0.9, 0.2>] [1 rgb <0.9, 0.9, 0.2>] } }
  finish { ambient 0.1 } }
plane { -z, -3
  pigment { checker rgb <0.8, 0.8, 0.8> rgb <0.3, 0.25, 0.35> scale 0.1 }
  finish { ambient 0.15 diffuse 0.7 } }
"""
