# SPDX-License-Identifier: AGPL-3.0-or-later
"""views: every decoded sub-aperture view as a float image with its ground-truth disparity, for
depth benchmarks (docs/export/views.md).

DIR/view_II_JJ.pfm       the view at angular row II, column JJ of the decoder's grid (only the
                         samples inside the usable microimage disc): linear-light RGB, float32,
                         PFM ('PF', little-endian, rows stored bottom first as netpbm says)
DIR/disparity_II_JJ.pfm  its disparity, float32 grey PFM ('Pf'), from the render's depth map
DIR/views.json           the views, their offsets, the geometry and the convention
DIR/README.md            the convention in words

The convention (also written into both files): a point seen at pixel (x, y) of view (i, j) is
seen at (x - d (j' - j), y - d (i' - i)) in view (i', j'), d its disparity in view pixels per
view step (one angular sample, `step` raw pixels). d > 0 in front of the plane the main lens
images onto the array, 0 on it, < 0 behind: the sign of the HCI benchmark's disparity, and the
same numbers as plenoptic-decode --hci writes for the same views. No offset: d is the shift
between the files as stored; nothing is added to it or is to be added. The reference view is the
centre view (its row and column in views.json).

The geometry is plenoptic_lf.hci's (HciGeometry, planar_depth_mm): behind a thin_lens or
thick_lens main lens and microlenses at d = f (plenoptic 1.0) the views are pinhole cameras on
the entrance pupil's plane looking at the plane in focus (a view samples every microimage at one
offset from its centre, so its chief rays all pass one point of the pupil). Hexagonal lens rows
are resampled to square view pixels one lens pitch apart, as for --hci: colours linearly between
rows, depths at the nearest row.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..hci import HciGeometry, check_pinhole_views, _nearest_samples, _resample_rows, _square_rows, planar_depth_mm
from ..lightfield import plan_decode
from . import ExportError, Render

SUMMARY = "every decoded view as a float PFM with a float disparity PFM each; the convention in views.json/README.md"
OPTIONS = {
    "angular": "angular samples per axis (odd); default the decoder's",
    "step": "angular sample spacing in raw pixels (default 1)",
}


def write_pfm(path: str | os.PathLike[str], values: np.ndarray) -> None:
    """float32 PFM by netpbm's rules: 'PF' (RGB, values (H, W, 3)) or 'Pf' (grey, (H, W)), then
    'width height', then -1 (little-endian), then the rows from the bottom up."""
    values = np.asarray(values)
    if values.dtype != np.float32:
        raise TypeError("PFM holds float32 values, got %s" % values.dtype)
    if values.ndim == 3 and values.shape[2] == 3:
        magic = b"PF"
    elif values.ndim == 2:
        magic = b"Pf"
    else:
        raise ValueError("PFM holds (H, W) or (H, W, 3) values, got %s" % (values.shape,))
    height, width = values.shape[:2]
    with open(path, "wb") as f:
        f.write(b"%s\n%d %d\n-1\n" % (magic, width, height))
        f.write(np.ascontiguousarray(values[::-1]).astype("<f4").tobytes())


def read_pfm(path: str | os.PathLike[str]) -> np.ndarray:
    """A PFM as float32 (H, W) or (H, W, 3), top row first; either byte order."""
    with open(path, "rb") as f:
        magic = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        data = f.read()
    channels = {b"PF": 3, b"Pf": 1}[magic]
    values = np.frombuffer(data, dtype="<f4" if scale < 0 else ">f4", count=width * height * channels)
    shape = (height, width, 3) if channels == 3 else (height, width)
    return values.reshape(shape)[::-1].astype(np.float32)


def check_views_camera(meta: Any) -> None:
    """ExportError unless every view is a pinhole camera on one grid with square pixels: the
    decoder's own check for --hci (hci.check_pinhole_views), in this format's name."""
    check_pinhole_views(meta, "views", ExportError)


README = """# Views with ground-truth disparity

Written by `plenoptic-export {image} --to views` (povray-plenoptic) from the render's ground
truth, not estimated. {count} views of {width} x {height} pixels.

Files
- `view_II_JJ.pfm`: the sub-aperture view at angular row II, column JJ: linear-light RGB,
  float32 PFM (`PF`, little-endian: the scale line is -1; rows stored bottom first, as netpbm's
  PFM says). No gamma, no 8-bit rounding.
- `disparity_II_JJ.pfm`: its disparity, float32 grey PFM (`Pf`). NaN where the render's ray was
  blocked (no depth).
- `views.json`: the list of views with their angular offsets, the geometry, this convention.

Convention
- Units: pixels of the view per view step (one angular sample: {step} raw pixel(s) between
  neighbouring views' microimage offsets).
- Sign: a point seen at (x, y) in view (i, j) is seen at (x - d (j' - j), y - d (i' - i)) in view
  (i', j'). d > 0 for points in front of the plane the main lens images onto the microlens array
  ({z0_m:.6g} m from the {pupil}), d = 0 on it, d < 0 behind it.
- Offset: none. d is the shift between the views as stored; no constant is added or is to be
  added. The views share the plane of zero disparity the optics give them (their sensors are, in
  the HCI benchmark's words, shifted); a method that wants the disparity of parallel cameras,
  baseline x focal / Z, adds {parallel:.6g} px (`geometry.parallel_cameras_add_px`).
- Reference view: the centre view, row {centre}, column {centre} (`view_{centre:02d}_{centre:02d}.pfm`).
  Every view has its own disparity map; each is the disparity of what that view sees.
- Geometry: the views are pinhole cameras {baseline_mm:.6g} mm apart on the {pupil}'s plane,
  with a focal length of {focal_px:.6g} view pixels; d = baseline x focal x (1/Z - 1/z0), Z the
  depth along the optical axis from that plane.
{rows}
"""


def export(render: Render, out_dir: Path, angular: int | None = None, step: float = 1.0) -> list[Path]:
    meta = render.meta
    check_views_camera(meta)
    depth_path = render.depth_map_path("views")
    plan_decode(meta, angular, step)
    distances = render.depth_map("views")
    lf = render.light_field(angular, step)
    plan = plan_decode(meta, len(lf.du), lf.step, lf.data.shape[-1])
    geometry = HciGeometry(meta, lf.step)
    T, S = lf.data.shape[:2]
    rows, height = _square_rows(meta, T)
    n = len(lf.du)
    centre = n // 2
    usable = [(i, j) for i in range(n) for j in range(n) if lf.mask[i, j]]
    render.progress.stage("views: %d views of %d x %d px with their disparity" % (len(usable), S, height))
    written: list[Path] = []
    entries = []
    for index, (i, j) in enumerate(usable):
        colour = _resample_rows(lf.view(i, j), rows, nearest=False).astype(np.float32)
        pixel_u, pixel_v, centre_u, centre_v = _nearest_samples(meta, plan, lf.du[j], lf.dv[i])
        depth = planar_depth_mm(meta, geometry, distances[pixel_v, pixel_u], pixel_u, pixel_v, centre_u, centre_v)
        disparity = geometry.disparity(_resample_rows(depth, rows, nearest=True)).astype(np.float32)
        name = "%02d_%02d" % (i, j)
        image_path = out_dir / ("view_%s.pfm" % name)
        disparity_path = out_dir / ("disparity_%s.pfm" % name)
        write_pfm(image_path, colour)
        write_pfm(disparity_path, disparity)
        written += [image_path, disparity_path]
        entries.append({"row": i, "column": j, "image": image_path.name, "disparity": disparity_path.name,
                        "offset_px": [float(lf.du[j]), float(lf.dv[i])]})
        render.progress.update(index + 1, len(usable))
    pupil = "main lens" if meta.main_lens_type == "thin_lens" else "entrance pupil"
    row_note = ("- Rows: the hexagonal lens grid's rows are resampled to square view pixels one lens pitch apart "
                "(colours linearly between rows, depths at the nearest row), as plenoptic-decode --hci does."
                if meta.grid == "hexagonal" else "- Rows: one lens row per view row (a rectangular lens grid).")
    doc = {
        "format": "plenoptic-export views",
        "render_image": os.path.basename(render.image_path),
        "render_metadata": os.path.basename(render.metadata_path),
        "render_depth_map": os.path.basename(depth_path),
        "image_format": "PFM float32: views 'PF' (linear RGB), disparities 'Pf'; little-endian, rows bottom first",
        "size_px": [S, height],
        "angular_samples": n,
        "angular_step_px": lf.step,
        "reference_view": {"row": centre, "column": centre},
        "convention": {
            "units": "view pixels per view step (one angular sample, angular_step_px raw pixels)",
            "sign": "a point at (x, y) in view (i, j) is at (x - d (j' - j), y - d (i' - i)) in view (i', j'); "
                    "d > 0 in front of the plane in focus",
            "offset": "none: d is the shift between the stored views; 0 on the plane the main lens images onto "
                      "the array",
            "invalid": "NaN where the render's ray was blocked",
        },
        "geometry": {
            "baseline_mm": geometry.baseline,
            "focal_length_px": geometry.focal_px,
            "focus_distance_mm": geometry.z0,
            "depth_from": pupil,
            "formula": "d = baseline_mm * focal_length_px * (1/Z - 1/focus_distance_mm), Z along the axis in mm",
            "parallel_cameras_add_px": geometry.baseline * geometry.focal_px / geometry.z0,
            "rows": "hexagonal rows resampled to square pixels one pitch apart" if meta.grid == "hexagonal"
                    else "one lens row per view row",
        },
        "views": entries,
    }
    json_path = out_dir / "views.json"
    with open(json_path, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")
    readme = out_dir / "README.md"
    with open(readme, "w", encoding="utf-8") as f:
        f.write(README.format(image=os.path.basename(render.image_path), count=len(usable), width=S, height=height,
                              step="%g" % lf.step, z0_m=geometry.z0 / 1000.0, pupil=pupil, centre=centre,
                              baseline_mm=geometry.baseline, focal_px=geometry.focal_px, rows=row_note,
                              parallel=geometry.baseline * geometry.focal_px / geometry.z0))
    return written + [json_path, readme]
