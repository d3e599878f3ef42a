# SPDX-License-Identifier: AGPL-3.0-or-later
"""kiel: the render as PlenopticToolbox 2.0's synthetic data (docs/export/raytrix.md, "The per-lens
JSON"): <stem>.json, a list with one object per microlens, and beside it lenses/, each lens's
colour image and depth image.

The fields are those PlenopticToolbox 2.0's reader of its synthetic data takes
(python/plenopticIO/imgIO.py, load_from_json; the lens image grid of python/microlens/lens.py,
LocalLensGrid), learnt by reading it:

  axial_coord             the lens's axial coordinates, the same as the raytrix export's XML
                          gives it (the toolbox's hexagonal lattice: along its lower-right, then
                          its right neighbour, from the lens nearest the picture's centre)
  pixel_coord             its microimage centre (row, column), pixels, centres at integers: the
                          render's measured centre (<stem>.microimages.csv) where it wrote one,
                          else the metadata lattice's
  diameter, lens_border   lens spacing and unused rim, pixels (as the raytrix XML)
  focal_type              our lens type (the raytrix XML's lens_type id)
  focal_length            d, the array-to-sensor distance (mm): the toolbox's disparity is
                          focal_length * diameter / depth, so with depth = v d it is diameter / v
  focus_distance          v_t d (mm), v_t = f / (f - d) the virtual depth the lens type focuses
  fstop                   the microlens's f-number f / pitch
  pixel_size              mm
  position, rotation_mat  the lens centre (mm) and the array's orientation in the frame x along
                          the picture's columns (u), y along its rows (v), z towards the scene,
                          origin at the main lens's centre (our optics frame with x mirrored: the
                          picture is read out turned by 180 degrees, docs/ground-truth.md)
  clip_start, clip_end    depth = stored / 65535 * (clip_end - clip_start) + clip_start, mm;
                          clip_start is 0, so a stored 0 means "no virtual depth" (the toolbox
                          takes only depth > 0)
  relative_color_filename, relative_depth_filename
                          lenses/<alpha>_<beta>.png (16-bit RGB) and lenses/<alpha>_<beta>_depth.png
                          (16-bit grey): the picture and the virtual depth times d sampled on the
                          lens's n x n grid, n = ceil(diameter), offsets linspace(-r, r, n) from the
                          centre (r = diameter / 2): bilinear for the colour, nearest for the depth

Needs the render's virtual depth map (depth_map on a focused, Galilean camera: d < f for every lens
type); refuses what the raytrix export refuses except measured centres off the lattice (every lens
has its own centre here)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from . import ExportError, Render
from .lenses import check_camera, lens_types, write_png16
from .raytrix import calibration

SUMMARY = "PlenopticToolbox 2.0's synthetic data: a per-lens JSON with each lens's colour and depth image"
OPTIONS: dict[str, str] = {}


def _bilinear(image: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    height, width = image.shape[:2]
    r = np.clip(rows, 0, height - 1)
    c = np.clip(cols, 0, width - 1)
    r0 = np.minimum(np.floor(r).astype(int), height - 2) if height > 1 else np.zeros_like(r, int)
    c0 = np.minimum(np.floor(c).astype(int), width - 2) if width > 1 else np.zeros_like(c, int)
    fr, fc = (r - r0)[..., None], (c - c0)[..., None]
    return ((1 - fr) * (1 - fc) * image[r0, c0] + (1 - fr) * fc * image[r0, c0 + 1] +
            fr * (1 - fc) * image[r0 + 1, c0] + fr * fc * image[r0 + 1, c0 + 1])


def array_rotation(render: Render) -> np.ndarray:
    """The array's rotation about z in the frame (u, v, towards the scene) = M Rz M, M = diag(-1, 1, 1)."""
    theta = math.radians(float(render.meta.raw["microlens_array"]["rotate_deg"][2]))
    c, s = math.cos(theta), math.sin(theta)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    m = np.diag([-1.0, 1.0, 1.0])
    return m @ rz @ m


def export(render: Render, out_dir: Path, **options: Any) -> list[Path]:
    meta = render.meta
    check_camera(render, "kiel")
    d = meta.array_distance_mm
    focal = lens_types(render)
    for t, f in enumerate(focal):
        if not f > d:
            raise ExportError("kiel: lens type %d has f = %g mm <= d = %g mm: the per-lens JSON's depths are positive "
                              "virtual depths times d (a Galilean camera, d < f for every type)" % (t, f, d))
    vd_path = meta.sidecar_path("virtual_depth_map")
    if vd_path is None:
        raise ExportError("kiel: the per-lens JSON needs each lens's depth, and this render wrote no virtual depth "
                          "map: add depth_map to the (focused) camera and render again")
    from ..images import read_depth_map
    v = read_depth_map(vd_path)
    if v is None or v.shape != (meta.height, meta.width):
        raise ExportError("kiel: cannot read the virtual depth map %s" % vd_path)
    # The lattice as the raytrix XML gives it (its checks, its axial coordinates), but each lens at
    # its own measured centre.
    cal = calibration(render, fmt="kiel", require_lattice=False)
    lenses = cal["lenses"]
    diameter, border = cal["diameter"], cal["lens_border"]
    alpha, beta = cal["axial"]
    n = int(math.ceil(diameter))
    offsets = np.linspace(-1.0, 1.0, n) * diameter / 2.0
    picture = render.picture()
    depth_mm = np.where(np.isfinite(v) & (v > 0), v.astype(np.float64) * d, 0.0)
    out = Path(out_dir)
    (out / "lenses").mkdir()
    rotation = array_rotation(render)
    p = meta.pitch_mm
    theta = math.radians(float(meta.raw["microlens_array"]["rotate_deg"][2]))
    tx, ty, tz = (float(x) for x in meta.raw["microlens_array"]["translate_mm"])
    lit = np.isfinite(lenses.mu) & np.isfinite(lenses.mv)
    crops = []
    for i in np.nonzero(lit)[0]:
        rows = lenses.mv[i] + offsets[:, None] + 0.0 * offsets[None, :]
        cols = lenses.mu[i] + offsets[None, :] + 0.0 * offsets[:, None]
        colour = _bilinear(picture, rows, cols)
        r = np.clip(np.floor(rows + 0.5).astype(int), 0, meta.height - 1)
        c = np.clip(np.floor(cols + 0.5).astype(int), 0, meta.width - 1)
        crops.append((i, colour, depth_mm[r, c]))
    clip_end = max([float(np.max(z)) for _, _, z in crops] + [0.0])
    if not clip_end > 0:
        raise ExportError("kiel: no lens sees a point at a positive virtual depth")
    written = []
    entries = []
    for i, colour, z in crops:
        name = "%d_%d" % (alpha[i], beta[i])
        colour_file = out / "lenses" / (name + ".png")
        depth_file = out / "lenses" / (name + "_depth.png")
        write_png16(colour_file, np.floor(np.clip(colour, 0.0, 1.0) * 65535.0 + 0.5))
        write_png16(depth_file, np.floor(z / clip_end * 65535.0 + 0.5))
        written += [colour_file, depth_file]
        t = int(lenses.type[i])
        f = focal[t]
        k, l = int(lenses.row_k[i]), int(lenses.l[i])
        # The lens centre in the optics frame (row form, docs/specification.md section 2), posed.
        x0, y0 = (k + (l % 2) / 2.0) * p, l * p * math.sqrt(3.0) / 2.0
        x = math.cos(theta) * x0 - math.sin(theta) * y0 + tx
        y = math.sin(theta) * x0 + math.cos(theta) * y0 + ty
        z_opt = -meta.main_distance_mm
        entries.append({
            "axial_coord": [int(alpha[i]), int(beta[i])],
            "pixel_coord": [float(lenses.mv[i]), float(lenses.mu[i])],
            "diameter": diameter, "lens_border": border, "focal_type": t,
            "focal_length": d, "focus_distance": f / (f - d) * d, "fstop": f / p,
            "pixel_size": float(meta.pixel_size_mm[0]),
            "position": [-x, y, z_opt], "rotation_mat": [float(w) for w in rotation.reshape(-1)],
            "clip_start": 0.0, "clip_end": clip_end,
            "relative_color_filename": "lenses/%s.png" % name,
            "relative_depth_filename": "lenses/%s_depth.png" % name,
            "row_form_index": [k, l],
        })
    json_path = out / (render.stem + ".json")
    json_path.write_text(json.dumps(entries, indent=1) + "\n", encoding="utf-8")
    render.progress.stage("kiel: %d lenses, %d x %d pixels each" % (len(entries), n, n))
    return [json_path] + written
