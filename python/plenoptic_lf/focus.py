# SPDX-License-Identifier: AGPL-3.0-or-later
"""The refocus sweep: which slopes to refocus at (from the render's depth map or a fixed reach),
slopes <-> distances, a focus measure, and choosing the 'near' and 'far' refocus and the EPI
row to show. Refocusing itself is LightField.refocus."""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from .images import read_depth_map

if TYPE_CHECKING:
    from .lightfield import LightField


def gray(image: npt.ArrayLike) -> np.ndarray:
    image = np.asarray(image, dtype=np.float64)
    if image.ndim == 3:
        return image[..., :3].mean(axis=-1)
    return image


def box3(x: npt.ArrayLike) -> np.ndarray:
    """3 x 3 box mean with edge replication (ndimage mode "nearest"). The sum of the nine
    neighbours, then one division: the same numbers, bit for bit, as adding the nine shifted
    copies of the edge-padded image in row order (uniform_filter's running sum would differ in
    the last bits)."""
    return ndimage.correlate(np.asarray(x), np.ones((3, 3)), mode="nearest") / 9.0


def laplacian_energy(image: npt.ArrayLike) -> np.ndarray:
    """Per-pixel squared Laplacian of the grey image, 3 x 3 box-smoothed (a focus measure)."""
    grey = gray(image)
    padded = np.pad(grey, 1, mode="edge")
    laplacian = padded[:-2, 1:-1] + padded[2:, 1:-1] + padded[1:-1, :-2] + padded[1:-1, 2:] - 4 * grey
    return box3(laplacian * laplacian)


def default_slopes(lf: LightField, count: int = 9, reach_lenses: float = 2.0) -> np.ndarray:
    """Slopes that shift the outermost usable views by -reach..+reach lenses."""
    half = max(np.abs(lf.du[np.any(lf.mask, axis=0)]).max() / lf.step, 1.0)
    limit = reach_lenses / half
    return np.linspace(-limit, limit, count)


def distance_to_slope(lf: LightField, distance: float) -> float | None:
    """Inverse of LightField.slope_to_distance (a main lens that forms an image; None otherwise)."""
    kappa = lf.meta.distance_to_kappa(distance)
    return None if kappa is None else lf.slope_from_kappa(kappa)


def slopes_from_depth_map(lf: LightField, count: int = 9) -> np.ndarray | None:
    """A sweep covering the scene's depths, when the render wrote a depth map (metadata field
    'depth_map', beside the metadata file) and the main lens forms an image: from the 2nd to the 98th
    percentile of the finite depths, widened by a quarter of the span on each side and always
    including slope 0. None when there is no usable depth map."""
    path = lf.meta.sidecar_path("depth_map")
    if path is None or lf.meta.focal_length_mm is None:
        return None
    depth = read_depth_map(path)
    if depth is None:
        return None
    finite = depth[np.isfinite(depth) & (depth > 0)]
    if finite.size < 10:
        return None
    ends = [distance_to_slope(lf, z) for z in np.percentile(finite, [2, 98])]
    known = [e for e in ends if e is not None]
    if len(known) < len(ends):
        return None
    lo, hi = min(known + [0.0]), max(known + [0.0])
    widen = max(0.25 * (hi - lo), 1e-3)
    return np.linspace(lo - widen, hi + widen, count)


def sharpest_slope_map(images: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Per pixel: index of the refocused image with the highest focus measure, and that measure."""
    energies = np.stack([laplacian_energy(im) for im in images])
    return np.argmax(energies, axis=0), energies.max(axis=0)


def pick_near_far(slopes: Sequence[float] | np.ndarray, best: np.ndarray, strength: np.ndarray) -> tuple[int, int]:
    """Indices of two slopes to show as 'near' and 'far' refocus: the two strongest modes of the
    per-pixel sharpest slope, at least two sweep steps apart; near is the smaller slope (closer to
    the camera). Without a second mode, the sweep end furthest from the first."""
    hist = np.bincount(best.ravel(), weights=strength.ravel(), minlength=len(slopes))
    first = int(np.argmax(hist))
    others = [i for i in range(len(slopes)) if abs(i - first) >= 2]
    second = max(others, key=lambda i: hist[i]) if others else first
    if not others or hist[second] < 0.05 * hist[first]:
        second = 0 if first >= len(slopes) / 2 else len(slopes) - 1
    near, far = sorted([first, second], key=lambda i: slopes[i])
    return near, far


def pick_epi_row(lf: LightField, best: np.ndarray, strength: np.ndarray) -> int:
    """The lens row for the EPI: much horizontal detail and, if any row has them, several depths."""
    cv, cu = lf.centre_index()
    centre = gray(lf.view(cv, cu))
    detail = np.abs(np.diff(centre, axis=1)).sum(axis=1)
    detail = detail / max(detail.max(), 1e-12)
    spread = np.zeros(len(detail))
    for t in range(len(detail)):
        strong = strength[t] > 0.2 * strength.max()
        if strong.sum() >= 4:
            spread[t] = np.percentile(best[t][strong], 90) - np.percentile(best[t][strong], 10)
    spread = spread / max(spread.max(), 1e-12)
    return int(np.argmax(detail + spread))
