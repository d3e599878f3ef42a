# SPDX-License-Identifier: AGPL-3.0-or-later
"""The total-focus (all-in-focus) image of a focused (2.0) plenoptic raw, from the virtual depth
the render wrote (<stem>.virtual_depth.exr) or one given (docs/total-focus.md).

Geometry (thin main lens, array parallel to the sensor; a thick_lens, a prescription's paraxial
equivalent, is the same with O the exit pupil's centre, D its distance to the array and the exit
pupil as the aperture, and gives the picture of a pinhole at the entrance pupil's centre).
A point of the array plane q = c + delta
(c: the centre of the lens whose cell holds it) looks, from the main lens's centre O, at the
scene point whose main-lens image X' lies on the line O -> q at virtual depth v (X' is v d
behind the array, v = -a / d). The line from X' through the lens centre c meets the sensor at

    s = m + delta (1/v + d/D),        m = c (1 + d/D) the microimage centre.

In pixels, with P the picture position "of q" (the lattice's continuous extension,
P - M(c) = delta (1 + d/D) in pixels): s = M(c) + (P - M(c)) (1/v + d/D) / (1 + d/D). Sampling every
P of a grid gives the picture a pinhole at O would take on a sensor D + d behind it: all in focus.
Each P is read in every lens near it (the nearest and its neighbours) that the main lens's cone
of light towards the point's image lights wholly, and the values are averaged (where no lens is
wholly lit, the nearest lens is read); v comes from the virtual depth map at the sample (a few fixed-point steps
from the microimage centre's), or is the constant given.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import DecodeError
from .images import bilinear, read_depth_map
from .metadata import Metadata


def check_total_focus_camera(meta: Metadata) -> None:
    """DecodeError unless the render is a focused camera behind a thin or thick main lens, array
    parallel to the sensor."""
    if meta.main_lens_type == "prescription":
        raise DecodeError("--total-focus reads each point from the microimages where an ideal lens's straight chief "
                          "ray through the exit pupil's centre puts it; this render's main lens is a traced "
                          "prescription, whose distortion and pupil aberration put it elsewhere, so the picture would "
                          "be wrong. Render the same camera with thick_lens (its paraxial equivalent) for a total "
                          "focus")
    if meta.main_lens_type not in ("thin_lens", "thick_lens"):
        raise DecodeError("--total-focus needs a thin_lens or thick_lens main lens; this render's is %s"
                          % meta.main_lens_type)
    array = meta.array
    focal = array.focal_lengths_mm
    if array.lens != "thin_lens" or all(math.isclose(f, meta.array_distance_mm, rel_tol=1e-9) for f in focal):
        raise DecodeError("--total-focus decodes focused (2.0) cameras (thin microlenses with d != f); this one is %s"
                          % ("a pinhole array" if array.lens != "thin_lens" else "a plenoptic 1.0 camera (d = f): "
                             "use its sub-aperture views"))
    rotate = array.rotate_deg
    if any(abs(r) > 0 for r in rotate[:2]):
        raise DecodeError("--total-focus needs an array parallel to the sensor; this one is tilted (rotate <%g, %g, %g>)"
                          % rotate)


def virtual_depth_path(meta: Metadata) -> str:
    """The render's virtual depth map beside its metadata; DecodeError when it wrote none."""
    return meta.required_sidecar("virtual_depth_map", "--total-focus", "virtual depth map",
                                 "--total-focus needs the virtual depth: render the focused camera with depth_map "
                                 "(which writes <stem>.virtual_depth.exr), or give a constant one with "
                                 "--virtual-depth V")


def _nearest_lattice(meta, P):
    """Skew lattice indices (k, l) of the microimage centre nearest to each P (..., 2)."""
    basis = np.column_stack([meta.a, meta.b])
    coords = (P - meta.origin) @ np.linalg.inv(basis).T
    base = np.floor(coords)
    best_k = best_l = best = None
    for dk in (0, 1):
        for dl in (0, 1):
            k, l = base[..., 0] + dk, base[..., 1] + dl
            centre = meta.origin + k[..., None] * meta.a + l[..., None] * meta.b
            distance = np.sum((P - centre) ** 2, axis=-1)
            if best is None:
                best_k, best_l, best = k, l, distance
            else:
                closer = distance < best
                best_k, best_l, best = np.where(closer, k, best_k), np.where(closer, l, best_l), np.minimum(distance, best)
    # On a hexagonal lattice the nearest centre can lie outside the four corners of the cell.
    for dk, dl in ((1, -1), (-1, 1)):
        k, l = best_k + dk, best_l + dl
        centre = meta.origin + k[..., None] * meta.a + l[..., None] * meta.b
        distance = np.sum((P - centre) ** 2, axis=-1)
        closer = distance < best
        best_k, best_l, best = np.where(closer, k, best_k), np.where(closer, l, best_l), np.minimum(distance, best)
    return best_k, best_l


def default_step(meta: Metadata, virtual: np.ndarray | float) -> float:
    """Output sample spacing (pixels of the picture) that reads the raw about one pixel apart at
    the scene's typical virtual depth: (1 + d/D) / k, k the median over the map of |1/v + d/D|
    (the scale from picture to raw at v)."""
    D, d = meta.pupil_distance_mm, meta.array_distance_mm
    values = np.asarray(virtual, dtype=np.float64).ravel()
    values = values[np.isfinite(values) & (np.abs(values) >= 1e-3)]
    scale = float(np.median(np.abs(1 / values + d / D))) if values.size else abs(0.5 + d / D)
    return (1 + d / D) / max(scale, 1e-6)


def total_focus(raw: np.ndarray, meta: Metadata, virtual: np.ndarray | float | None = None, step: float | None = None,
                iterations: int = 4) -> tuple[np.ndarray, float]:
    """raw (H, W, C) linear; virtual: the virtual depth map (H, W) or a number. Returns the image
    (rows, columns, C) and the step used (picture pixels between samples)."""
    if virtual is None:
        raise DecodeError("the total focus needs the virtual depth: the render's map (H, W) or one number")
    check_total_focus_camera(meta)
    # D: the exit pupil's centre (a thin lens's centre) to the array, from which the microimage
    # lattice projects the lens centres; the aperture below is the exit pupil's diameter.
    D, d = meta.pupil_distance_mm, meta.array_distance_mm
    constant = np.ndim(virtual) == 0
    if step is None:
        step = default_step(meta, virtual)
    if not (step > 0 and math.isfinite(step)):
        raise DecodeError("--total-focus-step must be a positive number of pixels, got %r" % (step,))
    columns = int(math.floor((meta.width - 1) / step)) + 1
    rows = int(math.floor((meta.height - 1) / step)) + 1
    if columns * rows > 50_000_000:
        raise DecodeError("the total-focus image would be %d x %d samples: use a larger --total-focus-step" % (columns, rows))
    yy, xx = np.mgrid[0:rows, 0:columns].astype(np.float64)
    P = np.stack([xx * step + 0.5 * ((meta.width - 1) - (columns - 1) * step),
                  yy * step + 0.5 * ((meta.height - 1) - (rows - 1) * step)], axis=-1)
    k0, l0 = _nearest_lattice(meta, P)
    H, W = raw.shape[:2]

    def centre_of(k, l):
        return meta.origin + k[..., None] * meta.a + l[..., None] * meta.b

    def sample_position(centre, v):
        return centre + (P - centre) * ((1 / v + d / D) / (1 + d / D))[..., None]

    def virtual_at(position):
        if constant:
            return np.full(position.shape[:-1], float(virtual))
        i = np.clip(np.rint(position[..., 0]), 0, W - 1).astype(np.intp)
        j = np.clip(np.rint(position[..., 1]), 0, H - 1).astype(np.intp)
        return virtual[j, i]

    # The virtual depth of what P shows: start from the nearest microimage's centre, then read the
    # map where the sample falls, a few times (it settles within a step on smooth surfaces).
    own = centre_of(k0, l0)
    v = virtual_at(own)
    for _ in range(iterations):
        bad = ~np.isfinite(v) | (np.abs(v) < 1e-3)
        v = np.where(bad, np.nan, v)
        v = virtual_at(sample_position(own, np.where(np.isnan(v), 1e9, v))) if not constant else v
    v = np.where(np.isfinite(v) & (np.abs(v) >= 1e-3), v, np.nan)

    # A lens images the point where the line from X' through its centre puts it only when the
    # main lens's cone of light towards X' covers its whole cell: the cone meets the array in a
    # disc of radius (A/2) |a| / b around q (a = -v d, b = D - a), and the lens centre lies
    # |P - M(c)| pixel / (1 + d/D) from q. Those lenses are averaged; where none is wholly lit
    # (a small cone), the nearest lens (whose cell holds q) is read.
    safe_v = np.where(np.isnan(v), 1e9, v)
    aperture = meta.exit_pupil_mm
    assert aperture is not None, "check_total_focus_camera: a thin or thick lens has an exit pupil"
    pixel = float(np.mean(meta.pixel_size_mm))
    circumradius = meta.pitch_mm / (math.sqrt(3) if meta.grid == "hexagonal" else math.sqrt(2))
    a = -safe_v * d
    cone = 0.5 * aperture * np.abs(a) / np.abs(D - a)
    total = np.zeros(P.shape[:-1] + (raw.shape[2],), np.float64)
    count = np.zeros(P.shape[:-1], np.float64)
    nearest: np.ndarray | None = None
    for dk in (-1, 0, 1):
        for dl in (-1, 0, 1):
            centre = centre_of(k0 + dk, l0 + dl)
            position = sample_position(centre, safe_v)
            offset_mm = np.hypot(*(P - centre).transpose(2, 0, 1)) * pixel / (1 + d / D)
            on_raw = (position[..., 0] >= 0) & (position[..., 0] <= W - 1) & (position[..., 1] >= 0) & (position[..., 1] <= H - 1)
            lit = (offset_mm + circumradius <= cone) & on_raw
            if dk == 0 and dl == 0:
                nearest = bilinear(raw, position[..., 0], position[..., 1])
            if not lit.any():
                continue
            values = bilinear(raw, position[..., 0], position[..., 1])
            total += np.where(lit[..., None], values, 0)
            count += lit
    assert nearest is not None  # the lens itself (dk = dl = 0) is always read
    total = np.where((count == 0)[..., None], nearest, total)
    count = np.maximum(count, 1)
    image = total / np.maximum(count, 1)[..., None]
    image[np.isnan(v)] = 0
    return image.astype(np.float32), step
