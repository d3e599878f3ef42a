# SPDX-License-Identifier: AGPL-3.0-or-later
"""The render's microlenses as the raytrix, kiel and compote exporters see them
(docs/export/raytrix.md, docs/export/compote.md): every lens whose microimage centre lies in the
picture, with its indices, lens type, focal length and centre, and the checks those formats share
(a hexagonal lattice of square pixels, not tilted, whose centres are the metadata's lattice).

Our conventions (docs/metadata.md): pixel (column i, row j) has its centre at (u, v) = (i, j), v
down; lenses in skew indices (k_s, l) with centre origin + k_s a + l b, row form k = k_s + floor(l/2);
multi-focus type (k_s - l) mod 3."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from . import ExportError, Render

# How far (pixels) a lens's measured centre (<stem>.microimages.csv) may lie from the lattice a
# format writes before the format refuses: the formats' own accuracy target.
CENTRE_TOLERANCE_PX = 0.01


@dataclass
class Lenses:
    """Every lens whose lattice centre lies in the picture. Arrays of one row per lens: skew
    index ks, row index l, row-form k (row_k), type (0 for one lens type), focal length (mm),
    lattice centre (u, v) and measured centre (mu, mv: microimages.csv where the render wrote it,
    else the lattice centre; NaN for a lens that gets no light)."""
    ks: np.ndarray
    l: np.ndarray
    row_k: np.ndarray
    type: np.ndarray
    focal_mm: np.ndarray
    u: np.ndarray
    v: np.ndarray
    mu: np.ndarray
    mv: np.ndarray
    measured: bool  # the centres come from microimages.csv


def _fail(fmt: str, why: str) -> ExportError:
    return ExportError("%s: %s" % (fmt, why))


def check_camera(render: Render, fmt: str, allow_real_lens: bool = False) -> None:
    """ExportError unless the render's lattice is one the hexagonal formats can write exactly: a
    main lens that forms an image, thin microlenses, a hexagonal grid, square pixels, an array not
    tilted about x or y (its lattice is then exact)."""
    meta = render.meta
    raw = meta.raw
    if meta.main_lens_type in ("none", "pinhole"):
        raise _fail(fmt, "the render has no image-forming main lens (main_lens.type %s): the format describes a "
                         "focused plenoptic camera (main lens, microlens array, sensor)" % meta.main_lens_type)
    if not allow_real_lens and meta.main_lens_type == "prescription":
        raise _fail(fmt, "the main lens is a traced prescription, whose distortion and pupil aberration the format "
                         "cannot express (its microimage centres leave the lattice); export a thin_lens or "
                         "thick_lens render")
    if not allow_real_lens and raw["main_lens"].get("distortion") is not None:
        raise _fail(fmt, "the thin main lens has distortion { }, which the format cannot express; export a render "
                         "without it")
    array = raw["microlens_array"]
    if meta.grid != "hexagonal":
        raise _fail(fmt, "the array is rectangular, and the format defines only a hexagonal microlens grid")
    if array.get("lens") != "thin_lens":
        raise _fail(fmt, "the microlenses are %s, and the format needs thin microlenses with focal lengths "
                         "(thin_lens)" % array.get("lens"))
    if not raw["microimage_lattice"].get("exact", False):
        raise _fail(fmt, "the array is tilted about x or y (microimage_lattice.exact is false): its microimages do "
                         "not form one lattice, which is all the format can describe")
    sx, sy = (float(v) for v in meta.pixel_size_mm)
    if abs(sx - sy) > 1e-12 * max(sx, sy):
        raise _fail(fmt, "the pixels are not square (%g x %g mm): the microimages then form a stretched hexagonal "
                         "lattice, which the format cannot describe" % (sx, sy))
    a, b = meta.a, meta.b
    lengths = [float(np.hypot(*w)) for w in (a, b, a - b)]
    if max(lengths) - min(lengths) > 1e-9 * max(lengths):
        raise _fail(fmt, "the microimage lattice is not a regular hexagonal one (neighbour spacings %s px)"
                         % ", ".join("%.9g" % x for x in lengths))


def lens_types(render: Render) -> tuple[float, ...]:
    return tuple(float(f) for f in render.meta.raw["microlens_array"]["focal_lengths_mm"])


def read_microimages_csv(path: str) -> dict[tuple[int, int], tuple[float, float]]:
    """{(row-form k, l): (u, v)} of <stem>.microimages.csv (docs/metadata.md), NaN for a dark lens."""
    out: dict[tuple[int, int], tuple[float, float]] = {}
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
        try:
            ik, il, iu, iv = (header.index(c) for c in ("k", "l", "u", "v"))
        except ValueError:
            raise ExportError("%s: not a microimages file (its header lacks k, l, u, v)" % path)
        for number, line in enumerate(f, start=2):
            words = line.rstrip("\n").split(",")
            if len(words) != len(header):
                raise ExportError("%s, line %d: %d fields, the header has %d" % (path, number, len(words), len(header)))
            try:
                out[(int(words[ik]), int(words[il]))] = (float(words[iu]) if words[iu] else math.nan,
                                                         float(words[iv]) if words[iv] else math.nan)
            except ValueError:
                raise ExportError("%s, line %d: k, l must be integers and u, v numbers" % (path, number))
    return out


def microimages_path(render: Render) -> str | None:
    entry = render.meta.raw.get("microimages")
    if not isinstance(entry, dict) or not isinstance(entry.get("file"), str):
        return None
    path = os.path.join(os.path.dirname(os.path.abspath(render.metadata_path)), entry["file"])
    if not os.path.exists(path):
        raise ExportError("the metadata names the microimage centres %s, which does not exist" % path)
    return path


def lenses_in_picture(render: Render, fmt: str, require_lattice: bool = True) -> Lenses:
    """The lenses whose lattice centre lies in the picture. With require_lattice, a render whose
    microimages.csv puts a lit lens more than CENTRE_TOLERANCE_PX from the lattice (manufacturing
    errors, a real lens) is refused, naming the worst lens: the lattice formats cannot express it."""
    meta = render.meta
    ks, l, u, v = meta.all_centres(margin=-0.5)  # the picture's pixels span [-0.5, W - 0.5)
    ks = ks.astype(np.int64)
    l = l.astype(np.int64)
    row_k = ks + np.floor_divide(l, 2)
    focal = lens_types(render)
    kind = np.mod(ks - l, 3) if len(focal) == 3 else np.zeros_like(ks)
    focal_mm = np.array([focal[t] for t in kind]) if focal else np.full(len(ks), math.nan)
    mu, mv = u.copy(), v.copy()
    path = microimages_path(render)
    if path is not None:
        centres = read_microimages_csv(path)
        for i, key in enumerate(zip(row_k.tolist(), l.tolist())):
            if key in centres:
                mu[i], mv[i] = centres[key]
        if require_lattice:
            error = np.hypot(mu - u, mv - v)
            lit = np.isfinite(error)
            if lit.any() and float(np.max(error[lit])) > CENTRE_TOLERANCE_PX:
                worst = int(np.nanargmax(np.where(lit, error, -1)))
                raise _fail(fmt, "the measured microimage centre of lens (%d, %d) (row form) lies %.4g px from the "
                                 "lattice (%s: manufacturing errors or a real lens), more than the %g px the format "
                                 "is written to; its one lattice cannot express that"
                            % (row_k[worst], l[worst], float(error[worst]), os.path.basename(path),
                               CENTRE_TOLERANCE_PX))
    return Lenses(ks, l, row_k, kind, focal_mm, u, v, mu, mv, path is not None)


def image_centre(render: Render) -> np.ndarray:
    """The picture's centre in our pixel convention (pixel centres at integers)."""
    return np.array([(render.meta.width - 1) / 2.0, (render.meta.height - 1) / 2.0])


def row_direction(render: Render) -> tuple[np.ndarray, float]:
    """The lattice vector along a row of the hexagonal lattice as a viewer sees it: of the six
    neighbour vectors, the one whose angle from +u, measured counter-clockwise on the screen (v
    down), lies in (-30, 30] degrees; with that angle in radians."""
    a, b = render.meta.a, render.meta.b
    best = None
    for w in (a, -a, b, -b, a - b, b - a):
        angle = math.atan2(-float(w[1]), float(w[0]))
        if -math.pi / 6 < angle <= math.pi / 6 + 1e-12:
            if best is None or abs(angle) < abs(best[1]):
                best = (np.array(w, dtype=float), angle)
    assert best is not None  # six vectors 60 degrees apart: one lies in every 60-degree window
    return best


def virtual_depth_in_focus(f_mm: float, d_mm: float) -> float:
    """The virtual depth (ours and Raytrix's: v = -a / d, positive behind the array) a thin
    microlens of focal length f at distance d from the sensor images sharply: blur
    (A/2)(d/f + 1/v - 1) = 0, v = f / (f - d); inf for d = f."""
    return math.inf if f_mm == d_mm else f_mm / (f_mm - d_mm)


def write_png16(path: str | os.PathLike[str], pixels: np.ndarray) -> None:
    """A 16-bit PNG of uint16 pixels (H, W) or (H, W, C), written by OpenImageIO."""
    from ..images import require_openimageio
    oiio = require_openimageio()
    pixels = np.ascontiguousarray(pixels, dtype=np.uint16)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    height, width, channels = pixels.shape
    out = oiio.ImageOutput.create(str(path))
    if out is None:
        raise ExportError("cannot write %s: %s" % (path, oiio.geterror()))
    spec = oiio.ImageSpec(width, height, channels, oiio.UINT16)
    spec.attribute("oiio:ColorSpace", "Linear")
    if not out.open(str(path), spec) or not out.write_image(pixels) or not out.close():
        raise ExportError("cannot write %s: %s" % (path, out.geterror()))
