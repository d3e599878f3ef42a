# SPDX-License-Identifier: AGPL-3.0-or-later
"""eslf: the decoded light field as LFToolbox's ESLF (docs/export/eslf.md).

<stem>.eslf.png: one 16-bit RGBA PNG of lenslet-major tiles. The decoder's light field
L[t, s, v, u, c] (t, s: lens row and column of its rectangular grid; v, u: angular sample; see
plenoptic_lf.lightfield) is laid out so that pixel (row t*n_v + v, column s*n_u + u) holds
L[t, s, v, u]: each lens is one n_v x n_u tile of its angular samples, the tiles in the lens
grid's order. This is the layout LFToolbox's LFReadESLF takes apart (a tile per lenslet, its size
the 'lenslet size'); LFToolbox names the same axes the other way round ([t, s, v, u] there are
angular row, angular column, spatial row, spatial column).

Values: linear light (no gamma), each 16-bit value round(clip(L * scale, 0, 1) * 65535), as
LFToolbox's conversion of a float light field in [0, 1] to uint16 rounds it; scale 1 unless
-O scale says otherwise (a light field brighter than 1 is refused, never clipped silently). The
alpha channel is LFToolbox's weight channel: 65535 where the sample lies in the usable microimage
disc of a lens that gets light, 0 elsewhere (samples outside the disc are still written).

<stem>.eslf.png.json (LFToolbox reads <file>.json beside an ESLF): DecodeOptions.LFSize (the
lenslet size, so no one guesses the pitch), LensletGridModel where LFToolbox's hexagonal model
describes the render's microimage lattice exactly (else null and why), and our own record of the
grid, the resampling and the quantisation under "plenoptic"."""

from __future__ import annotations

import json
import math
import os
import struct
import zlib
from pathlib import Path
from typing import Any, Iterable, Iterator

import numpy as np

from . import ExportError, Render

SUMMARY = "LFToolbox's ESLF: 16-bit PNG of lenslet-major tiles of the decoded light field, with its .json"
OPTIONS = {
    "angular": "angular samples per axis (odd): the tile size; default the decoder's",
    "step": "angular sample spacing in raw pixels (default 1)",
    "scale": "a number, or auto (1 / the largest value): stored value = round(clip(L x scale, 0, 1) x 65535); "
             "default 1, and a light field brighter than 1 is refused",
}

FULL = 65535


def quantise(values: np.ndarray, scale: float) -> np.ndarray:
    """Linear float -> uint16: round(clip(values x scale, 0, 1) x 65535), halves away from zero
    (every value here is >= 0, so floor(x + 0.5))."""
    scaled = np.clip(np.asarray(values, np.float64) * scale, 0.0, 1.0) * FULL
    return np.floor(scaled + 0.5).astype(np.uint16)


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def write_png16(path: str | os.PathLike[str], width: int, height: int, channels: int,
                bands: Iterable[np.ndarray], progress: Any = None) -> None:
    """A 16-bit PNG (RGB or RGBA) of `height` rows of `width` uint16 pixels, given as bands of
    whole rows (each (rows, width, channels)) so that the image need not exist whole in memory;
    with gAMA 1.0 (linear values). Written here by PNG's own rules: big-endian samples, filter 0
    on every row, one zlib stream in one IDAT chunk."""
    colour_type = {3: 2, 4: 6}[channels]
    compressor = zlib.compressobj(6)
    parts = []
    done = 0
    for band in bands:
        rows = band.shape[0]
        if band.shape[1:] != (width, channels):
            raise ValueError("a band of %s pixels in a %d x %d x %d PNG" % (band.shape, width, height, channels))
        body = np.zeros((rows, width * channels * 2 + 1), np.uint8)
        body[:, 1:] = np.ascontiguousarray(band.astype(">u2")).view(np.uint8).reshape(rows, -1)
        parts.append(compressor.compress(body.tobytes()))
        done += rows
        if progress is not None:
            progress.update(done, height)
    if done != height:
        raise ValueError("%d rows given for a PNG of %d" % (done, height))
    parts.append(compressor.flush())
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 16, colour_type, 0, 0, 0)))
        f.write(_chunk(b"gAMA", struct.pack(">I", 100000)))
        f.write(_chunk(b"IDAT", b"".join(parts)))
        f.write(_chunk(b"IEND", b""))


def lenslet_grid_model(meta: Any) -> tuple[dict[str, Any] | None, str]:
    """LFToolbox's LensletGridModel (HSpacing, VSpacing, HOffset, VOffset, Rot, Orientation,
    FirstPosShiftRow, UMax, VMax; 1-based MATLAB pixel coordinates) of the render's microimage
    lattice, and a sentence: why it is exact, or (model None) why the model cannot describe it."""
    if meta.grid != "hexagonal":
        return None, ("LFToolbox's lenslet grid model is hexagonal only (every other row half a lens to the side); "
                      "this render's lattice is %s, recorded under plenoptic.microimage_lattice instead" % meta.grid)
    a, b = np.asarray(meta.a, float), np.asarray(meta.b, float)
    r = b - 0.5 * a  # from one row to the next, at right angles to the rows on an ideal array
    if a[0] < 0 or (a[0] == 0 and a[1] < 0):
        a = -a
    if r[1] < 0:
        r = -r
    spacing = math.hypot(*a)
    angle = math.atan2(a[1], a[0])
    # LFToolbox rotates the grid by Rot about its first lens: rows along (cos, sin), row steps
    # along (-sin, cos), VSpacing apart.
    down = np.array([-math.sin(angle), math.cos(angle)])
    row_spacing = float(r @ down)
    if (abs(float(r @ a)) > 1e-9 * spacing * spacing
            or abs(row_spacing - spacing * math.sqrt(3) / 2) > 1e-9 * spacing):
        return None, ("LFToolbox's lenslet grid model has rows sqrt(3)/2 of a lens spacing apart, at right angles "
                      "to them; this render's lattice (basis %s, %s px) is not that shape on the sensor (non-square "
                      "pixels or a sheared array), recorded under plenoptic.microimage_lattice instead"
                      % (list(map(float, meta.a)), list(map(float, meta.b))))
    W, H = meta.width, meta.height
    origin = np.asarray(meta.origin, float)
    # Row index l' = (position - origin) . down / row_spacing; the first row whose centres lie in the image.
    corners = np.array([[0, 0], [W - 1, 0], [0, H - 1], [W - 1, H - 1]], float) - origin
    rows_at = corners @ down / row_spacing
    along = corners @ np.array([math.cos(angle), math.sin(angle)]) / spacing
    first_row = math.ceil(rows_at.min() - 1e-9)
    # Lens k' of row l' sits at origin + l' r + (k' + shift(l')) a, shift = 0.5 l' mod 1.

    def first_lens(row: int) -> np.ndarray | None:
        """Of row `row`'s lenses whose centres lie in the image, the one furthest left along the rows."""
        shift = (0.5 * row) % 1.0
        ks = np.arange(math.floor(along.min()) - 2, math.ceil(along.max()) + 3) + shift
        points = origin + row * r + ks[:, None] * a
        inside = (points[:, 0] >= 0) & (points[:, 0] <= W - 1) & (points[:, 1] >= 0) & (points[:, 1] <= H - 1)
        points = points[inside]
        return points[np.argmin(points @ unit)] if len(points) else None

    unit = np.array([math.cos(angle), math.sin(angle)])
    # The first row (from the top, across the rows) with a centre in the image.
    while first_row <= rows_at.max() and first_lens(first_row) is None:
        first_row += 1
    p1, p2 = first_lens(first_row), first_lens(first_row + 1)
    if p1 is None or p2 is None:
        return None, "fewer than two rows of microimage centres lie in the image"
    # HOffset, VOffset: a grid point of the first row; the rows LFToolbox shifts by +HSpacing/2
    # are the second, fourth... (FirstPosShiftRow 2) when the first row starts further left,
    # else the first, third... (FirstPosShiftRow 1, the grid point then half a lens left of its first lens).
    if float((p2 - p1) @ unit) > 0:
        start, shifted_row = p1, 2
    else:
        start, shifted_row = p2 - r, 1
    h_offset, v_offset = float(start[0]) + 1.0, float(start[1]) + 1.0
    model = {
        "HSpacing": spacing,
        "VSpacing": row_spacing,
        "HOffset": h_offset,
        "VOffset": v_offset,
        "Rot": angle,
        "Orientation": "horz",
        "FirstPosShiftRow": shifted_row,
        # As LFToolbox counts them: the grid's columns and rows from the offset to the image's edge.
        "UMax": int(math.floor((W - h_offset) / spacing)) + 1,
        "VMax": int(math.floor((H - v_offset) / row_spacing)) + 1,
    }
    return model, ("exact: the render's microimage lattice (metadata microimage_lattice), in LFToolbox's 1-based "
                   "pixel coordinates (pixel (1, 1) is our pixel (0, 0))")


def _scale_option(value: Any, largest: float) -> float:
    if value is None:
        if largest > 1.0:
            raise ExportError("the light field's largest value is %.6g, above 1: ESLF's 16-bit values hold 0..1 and "
                              "brighter samples would be clipped; pass -O scale=auto (1 / the largest value) or "
                              "-O scale=NUMBER" % largest)
        return 1.0
    if str(value).strip().lower() == "auto":
        return 1.0 / largest if largest > 0 else 1.0
    try:
        scale = float(value)
    except ValueError:
        raise ExportError("-O scale takes a positive number or auto, found %r" % value) from None
    if not (math.isfinite(scale) and scale > 0):
        raise ExportError("-O scale takes a positive number or auto, found %r" % value)
    if largest * scale > 1.0:
        raise ExportError("-O scale=%s puts the largest value at %.6g, above 1: ESLF's 16-bit values hold 0..1; "
                          "pass a scale up to %.6g or auto" % (value, largest * scale, 1.0 / largest))
    return scale


def check_eslf_camera(meta: Any) -> None:
    """ExportError unless the decoder's tiles are sub-aperture samples, the 4-D light field an ESLF
    holds: microlenses focused at infinity (d = f, plenoptic 1.0) or pinholes. A focused (2.0)
    camera's microimages are small pictures of the scene, not a lens's directions."""
    array = meta.array
    if array.lens == "pinhole":
        return
    wrong = [f for f in array.focal_lengths_mm if not math.isclose(meta.array_distance_mm, f, rel_tol=1e-6)]
    if wrong:
        raise ExportError("eslf holds a 4-D light field of sub-aperture samples (plenoptic 1.0: array to sensor "
                          "distance d = microlens focal length f); this camera has d = %g mm and microlens focal "
                          "length%s %s mm, a focused (2.0) camera whose microimages are pictures of the scene, not "
                          "directions: its tiles would not be a light field LFToolbox can use"
                          % (meta.array_distance_mm, "s" if len(array.focal_lengths_mm) > 1 else "",
                             ", ".join("%g" % f for f in array.focal_lengths_mm)))


def export(render: Render, out_dir: Path, angular: int | None = None, step: float = 1.0,
           scale: Any = None) -> list[Path]:
    meta = render.meta
    check_eslf_camera(meta)
    lf = render.light_field(angular, step)
    T, S, n_v, n_u, C = lf.data.shape
    if C != 3:
        raise ExportError("ESLF holds RGB tiles; this light field has %d channels" % C)
    largest = float(lf.data.max()) if lf.data.size else 0.0
    factor = _scale_option(scale, largest)
    render.progress.stage("ESLF: %d x %d lenslets of %d x %d samples -> %d x %d px, 16-bit RGBA"
                          % (S, T, n_u, n_v, S * n_u, T * n_v))

    def lens_rows() -> Iterator[np.ndarray]:
        """The image one lens row (n_v pixel rows) at a time: tiles [v, s, u, c] side by side."""
        for t in range(T):
            band = np.empty((n_v, S, n_u, 4), np.uint16)
            band[..., :3] = quantise(lf.data[t], factor).transpose(1, 0, 2, 3)
            weight = lf.mask[None, :, :] & ~lf.dark[t][:, None, None]  # [s, v, u]
            band[..., 3] = np.where(weight, FULL, 0).transpose(1, 0, 2)
            yield band.reshape(n_v, S * n_u, 4)

    png = out_dir / ("%s.eslf.png" % render.stem)
    write_png16(png, S * n_u, T * n_v, 4, lens_rows(), render.progress)

    model, model_note = lenslet_grid_model(meta)
    s0, t0 = lf.origin_st
    doc = {
        "DecodeOptions": {"LFSize": [n_v, n_u, T, S, 4]},
        "LensletGridModel": model,
        "plenoptic": {
            "format": "plenoptic-export eslf",
            "render_image": os.path.basename(render.image_path),
            "render_metadata": os.path.basename(render.metadata_path),
            "layout": "pixel (row t*n_v + v, column s*n_u + u) holds L[t, s, v, u]: one n_v x n_u tile per lenslet "
                      "(its angular samples), tiles in lens-grid order (t rows down, s columns right)",
            "lenslet_size_px": [n_v, n_u],
            "lenslets": [T, S],
            "angular_step_px": lf.step,
            "angular_offsets_px": [float(x) for x in lf.du],
            "usable_samples": "alpha 65535: inside the usable microimage disc of a lit lens; 0 otherwise",
            "values": "linear light; stored = round(clip(L x scale, 0, 1) x 65535)",
            "scale": factor,
            "lenslet_grid_model": model_note,
            "microimage_lattice": {
                "grid": meta.grid,
                "origin_px": [float(x) for x in meta.origin],
                "basis_px": [[float(x) for x in meta.a], [float(x) for x in meta.b]],
                "microimage_pitch_px": float(math.hypot(*meta.a)),
                "pixel_coordinates": "0-based, pixel centres at integers (the metadata's)",
            },
            "resampled_grid": {
                "lens_position_px": "raw pixel of tile (t, s): origin_px + (s0 + s) A + (t0 + t) R",
                "A_px": [float(x) for x in lf.A],
                "R_px": [float(x) for x in lf.R],
                "s0_t0": [float(s0), float(t0)],
                "spatial_aspect": float(lf.display_aspect()),
                "resampling": ("hexagonal rows: every other row half a lens to the side, its samples interpolated "
                               "linearly between the row's two neighbouring lenses; tiles are |R|/|A| = sqrt(3)/2 "
                               "as tall as wide on the sensor" if meta.grid == "hexagonal" else
                               "none: one tile per lens"),
            },
            "microlens_pitch_mm": meta.pitch_mm,
            "pixel_size_mm": [float(x) for x in meta.pixel_size_mm],
        },
    }
    sidecar = out_dir / ("%s.eslf.png.json" % render.stem)
    with open(sidecar, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")
    return [png, sidecar]
