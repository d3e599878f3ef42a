# SPDX-License-Identifier: AGPL-3.0-or-later
"""Raw lenslet image + metadata -> 4-D light field; sub-aperture views, refocusing by
shift-and-add and epipolar-plane images.

Every microimage is sampled on a regular grid of (u, v) offsets around its centre and the
samples are arranged as

    L[t, s, v, u, c]     t, s: lens row and column (a rectangular grid, row t top to bottom,
                               column s left to right, as the picture shows them)
                         v, u: angular sample, offset (dv, du) pixels from the microimage
                               centre (u to the right, v downwards, as in the raw image)
                         c:    colour channel (R, G, B), linear light

Hexagonal lattices are resampled to the rectangular (s, t) grid: every other lens row sits
half a lens to the side, so its values are interpolated linearly between its two neighbours
in that row.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from .errors import DecodeError, MetadataError
from .images import bilinear
from .metadata import Metadata
from .microimages import microimage_centre
from .progress import Progress


class LightField:
    """A decoded light field and the geometry needed to use it.

    data:     float32 L[t, s, v, u, c]
    du, dv:   angular offsets of the u and v samples, pixels from the microimage centre
    mask:     bool [v, u], True where the offset lies inside the usable microimage disc
    A, R:     pixel vectors between neighbouring (s) and (t) grid positions on the sensor
    position: (s, t) -> raw pixel of that grid point: origin + (s0 + s) A + (t0 + t) R
              (of the metadata lattice; behind a traced prescription each microimage was
              sampled around its measured centre, which lies off it by up to a pixel or so)
    dark:     bool [t, s], True at grid points whose lens gets no light (measured centres)
    """

    def __init__(self, data: np.ndarray, du: np.ndarray, dv: np.ndarray, mask: np.ndarray, A: np.ndarray,
                 R: np.ndarray, origin_st: tuple[float, float], meta: Metadata, step: float) -> None:
        self.data = data
        self.du = du
        self.dv = dv
        self.mask = mask
        self.A = A
        self.R = R
        self.origin_st = origin_st  # (s0, t0): grid index of data[0, 0]
        self.meta = meta
        self.step = step
        self.M = np.column_stack([A, R])
        self.M_inv = np.linalg.inv(self.M)
        self.dark = np.zeros(data.shape[:2], bool)

    @property
    def shape(self) -> tuple[int, ...]:
        return self.data.shape

    def centre_index(self) -> tuple[int, int]:
        return len(self.dv) // 2, len(self.du) // 2

    def view(self, iv: int, iu: int) -> np.ndarray:
        """Sub-aperture view (T, S, C) at angular sample (iv, iu)."""
        return self.data[:, :, iv, iu, :]

    def grid_position(self, s: npt.ArrayLike, t: npt.ArrayLike) -> np.ndarray:
        """Raw-image pixel position of grid point (s, t) (indices into data)."""
        s0, t0 = self.origin_st
        s = (s0 + np.asarray(s, float))[..., None]
        t = (t0 + np.asarray(t, float))[..., None]
        return self.meta.origin + s * self.A + t * self.R

    def kappa(self, slope: float) -> float:
        """Refocus slope (lenses along s per angular step) -> microimage-centre pixels per pixel."""
        return slope * np.hypot(*self.A) / self.step

    def slope_from_kappa(self, kappa: float) -> float:
        return kappa * self.step / np.hypot(*self.A)

    def shift_for(self, slope: float, iv: int, iu: int) -> tuple[float, float]:
        """(ds, dt) grid shift of view (iv, iu) that aligns a point with this slope."""
        kappa = self.kappa(slope)
        ds, dt = self.M_inv @ (kappa * np.array([self.du[iu], self.dv[iv]]))
        return ds, dt

    def refocus(self, slope: float) -> np.ndarray:
        """Shift-and-add over all usable views: the picture focused where points move by
        `slope` lenses along s per angular step (0: the plane imaged onto the array)."""
        T, S = self.data.shape[:2]
        tt, ss = np.meshgrid(np.arange(T, dtype=float), np.arange(S, dtype=float), indexing="ij")
        total = np.zeros((T, S, self.data.shape[-1]), np.float32)
        weight = np.zeros((T, S, 1), np.float32)
        for iv in range(len(self.dv)):
            for iu in range(len(self.du)):
                if not self.mask[iv, iu]:
                    continue
                ds, dt = self.shift_for(slope, iv, iu)
                x = ss + ds
                y = tt + dt
                inside = ((x >= 0) & (x <= S - 1) & (y >= 0) & (y <= T - 1)).astype(np.float32)[..., None]
                total += bilinear(self.view(iv, iu), x, y) * inside
                weight += inside
        return total / np.maximum(weight, 1e-6)

    def epi(self, t: int, iv: int | None = None) -> tuple[np.ndarray, list[int]]:
        """Horizontal epipolar-plane image at lens row t and angular row iv (default centre):
        array (n_u, S, C), u down, s across, only the usable u samples; and the list of those
        u sample indices."""
        if iv is None:
            iv = len(self.dv) // 2
        usable_u = [iu for iu in range(len(self.du)) if self.mask[iv, iu]]
        return np.stack([self.data[t, :, iv, iu, :] for iu in usable_u], axis=0), usable_u

    def slope_to_distance(self, slope: float) -> float | None:
        return self.meta.slope_to_distance(self.kappa(slope))

    def display_aspect(self) -> float:
        """Height/width of one (s, t) grid cell on the sensor (sqrt(3)/2 for hexagonal grids)."""
        return np.hypot(*self.R) / np.hypot(*self.A)


def _rectangular_grid_axes(meta):
    """Row vectors of the rectangular lens grid: A along the lens rows pointing right in the
    image, R from one row to the next pointing down; and the skew coefficients so that
    origin + s A + t R = origin + (s*sa - t*rho*h) a + (t*rho) b.
    Returns (A, R, sa, rho, h)."""
    a = meta.a
    h = 0.5 if meta.grid == "hexagonal" else 0.0
    sa = 1.0 if (a[0] > 0 or (a[0] == 0 and a[1] > 0)) else -1.0
    r = meta.b - h * a
    rho = 1.0 if r[1] >= 0 else -1.0
    return sa * a, rho * r, sa, rho, h


# The largest light field the decoder builds: L in float32, refused up front beyond this (a whole
# run needs about 1.5 times L plus the raw image; docs/ground-truth.md).
LIGHT_FIELD_LIMIT_BYTES = 4 * 1024 ** 3


def _usable_radius(meta):
    """Radius (pixels) of the usable microimage disc: the smaller of the main-aperture disc
    (microimage_diameter_px / 2) and the microimage cell's inradius, less one pixel."""
    # Inradius of a microimage cell: half the distance to the nearest neighbouring centre.
    if meta.grid == "rectangular":
        radius = 0.5 * min(np.hypot(*meta.a), np.hypot(*meta.b))
    else:
        radius = 0.5 * np.hypot(*meta.a)
    if meta.diameter_px is not None and meta.diameter_px > 0:
        radius = min(radius, 0.5 * meta.diameter_px)
    return radius - 1.0


def _angular_count(usable: float, n: int | None, step: float) -> int:
    """Samples per axis: n (checked) or as many `step`-pixel steps as fit the usable radius."""
    if n is None:
        ratio = usable / step + 1e-9
        half = max(int(math.floor(min(ratio, 1e12))), 0) if not math.isnan(ratio) else 0
        n = 2 * half + 1
    if n < 1 or n % 2 == 0:
        raise DecodeError("the angular sample count must be odd and positive, got %d" % n)
    return n


def _angular_offsets(n, step):
    return (np.arange(n) - n // 2) * float(step)


def angular_grid(meta: Metadata, n: int | None = None, step: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Offsets (pixels) of the angular samples and the usable-disc mask: (du, dv, mask).

    The usable radius is the smaller of the main-aperture disc (microimage_diameter_px / 2) and
    the microimage cell's inradius, less one pixel so that every sample is fully lit.
    n (odd) overrides the count."""
    usable = _usable_radius(meta)
    n = _angular_count(usable, n, step)
    offsets = _angular_offsets(n, step)
    dv, du = np.meshgrid(offsets, offsets, indexing="ij")
    mask = np.hypot(du, dv) <= max(usable, 0.0) + 1e-9
    mask[n // 2, n // 2] = True
    return offsets.copy(), offsets.copy(), mask


def _gib(n_bytes):
    return "%.3g GiB" % (n_bytes / 1024.0 ** 3)


class DecodePlan:
    """What decode() will build, computed from the metadata alone (no pixels, nothing large):
    n (angular samples per axis), reach (largest usable offset, pixels), the rectangular lens
    grid (A, R, its skew coefficients), the kept lenses (k0, frac, l: T x S arrays) and
    origin_st, shape (T, S, n, n, C) and nbytes of L in float32."""

    def __init__(self, meta: Metadata, n: int | None = None, step: float = 1.0, channels: int = 3,
                 limit_bytes: int = LIGHT_FIELD_LIMIT_BYTES) -> None:
        W, H = meta.width, meta.height
        self.step = float(step)
        if not (self.step > 0 and math.isfinite(self.step)):
            raise DecodeError("the angular step must be a positive number of pixels, got %r" % (step,))
        A, R, sa, rho, h = _rectangular_grid_axes(meta)
        self.A, self.R = A, R
        grid_inverse = np.linalg.inv(np.column_stack([A, R]))
        corners = np.array([[0, 0], [W - 1, 0], [0, H - 1], [W - 1, H - 1]], float) - meta.origin
        corners_st = corners @ grid_inverse.T
        if not np.isfinite(corners_st).all():
            raise DecodeError("the metadata lattice puts no sensible grid of microimages on the %d x %d image" % (W, H))
        # Microimages farther apart than the image is wide or high: at most one lens per row or
        # column, no light field (and, unchecked, an angular grid as large as a microimage).
        extent_s, extent_t = np.ptp(corners_st[:, 0]), np.ptp(corners_st[:, 1])
        if extent_s < 1.0 or extent_t < 1.0:
            raise DecodeError(
                "field 'microimage_lattice.basis_px' puts microimages %.1f px apart along a lens row and %.1f px "
                "between rows, more than the %d x %d px image spans (%.2f x %.2f spacings; microlens_array.pitch_mm "
                "%s, sensor.pixel_size_mm %s): at most one lens per row or column, no light field to decode"
                % (np.hypot(*A), np.hypot(*R), W, H, extent_s, extent_t,
                   "%g" % meta.pitch_mm, "%g" % meta.pixel_size_mm[0]))
        if extent_s * extent_t > 4.0 * W * H:
            raise DecodeError("the metadata lattice puts no sensible grid of microimages on the %d x %d image" % (W, H))

        # The angular grid's size, before building it: even one lens must fit the limit.
        usable = _usable_radius(meta)
        self.n = n = _angular_count(usable, n, self.step)
        self.channels = channels
        per_lens = n * n * channels * 4
        if per_lens > limit_bytes:
            raise DecodeError(
                "one microimage alone would give %d x %d angular samples (%s per lens in float32, over the "
                "decoder's limit of %s for the light field): use a larger --step (now %g px) or a smaller --angular"
                % (n, n, _gib(per_lens), _gib(limit_bytes), self.step))
        offsets = _angular_offsets(n, self.step)
        usable_offsets = np.abs(offsets)[np.abs(offsets) <= max(usable, 0.0) + 1e-9]
        self.reach = reach = float(usable_offsets.max()) if usable_offsets.size else 0.0

        s_all = np.arange(math.floor(corners_st[:, 0].min()) - 1, math.ceil(corners_st[:, 0].max()) + 2)
        t_all = np.arange(math.floor(corners_st[:, 1].min()) - 1, math.ceil(corners_st[:, 1].max()) + 2)
        ss, tt = np.meshgrid(s_all, t_all)
        # Skew index of every grid point: lens (k0, l) and, for a hexagonal half-shifted row, the
        # fraction `frac` of the way to lens (k0 + 1, l).
        k = ss * sa - tt * rho * h
        l = tt * rho
        k0 = np.floor(k + 1e-9)
        frac = k - k0

        def inside(kk, ll):
            u, v, _ = microimage_centre(meta, kk, ll)
            return (u - reach >= 0) & (u + reach <= W - 1) & (v - reach >= 0) & (v + reach <= H - 1)

        valid = inside(k0, l) & ((frac < 1e-6) | inside(k0 + 1, l))
        # Largest rectangle of grid points whose microimages lie wholly in the picture (greedy).
        t_lo, t_hi, s_lo, s_hi = 0, valid.shape[0] - 1, 0, valid.shape[1] - 1
        while t_lo <= t_hi and s_lo <= s_hi and not valid[t_lo:t_hi + 1, s_lo:s_hi + 1].all():
            invalid = ~valid[t_lo:t_hi + 1, s_lo:s_hi + 1]
            losses = [invalid[0].mean(), invalid[-1].mean(), invalid[:, 0].mean(), invalid[:, -1].mean()]
            side = int(np.argmax(losses))
            if side == 0:
                t_lo += 1
            elif side == 1:
                t_hi -= 1
            elif side == 2:
                s_lo += 1
            else:
                s_hi -= 1
        if t_lo > t_hi or s_lo > s_hi:
            raise DecodeError("no microimage lies wholly inside the %d x %d image" % (W, H))
        kept = (slice(t_lo, t_hi + 1), slice(s_lo, s_hi + 1))
        self.k0, self.frac, self.l = k0[kept], frac[kept].astype(np.float32), l[kept]
        self.origin_st = (s_all[s_lo], t_all[t_lo])
        T, S = self.k0.shape
        self.shape = (T, S, n, n, channels)
        self.nbytes = T * S * per_lens
        if self.nbytes > limit_bytes:
            raise DecodeError(
                "the light field would be %d x %d lenses x %d x %d angular samples x %d colours = %s in float32, "
                "over the decoder's limit of %s: use a larger --step (now %g px) or a smaller --angular"
                % (T, S, n, n, channels, _gib(self.nbytes), _gib(limit_bytes), self.step))


def plan_decode(meta: Metadata, n: int | None = None, step: float = 1.0, channels: int = 3) -> DecodePlan:
    """The DecodePlan of decode(raw, meta, n, step) from the metadata alone: the light field's
    shape and size, checked. Raises DecodeError when the microimage spacing exceeds the image,
    no microimage fits, or L would exceed LIGHT_FIELD_LIMIT_BYTES."""
    return DecodePlan(meta, n, step, channels)


def decode(raw: np.ndarray, meta: Metadata, n: int | None = None, step: float = 1.0,
           progress: Progress | None = None) -> LightField:
    """Raw image (H, W, C float) + Metadata -> LightField.

    n: angular samples per axis (odd; default as many `step`-pixel steps as fit the usable
    microimage disc); progress: a Progress for stage messages (default silent). The size is
    checked first (plan_decode): DecodeError instead of an absurd allocation."""
    if progress is None:
        progress = Progress(False)
    H, W = raw.shape[:2]
    if (W, H) != (meta.width, meta.height):
        raise MetadataError("fields 'image.width' x 'image.height' are %d x %d but the raw image is %d x %d"
                            % (meta.width, meta.height, W, H))
    C = raw.shape[2]
    plan = plan_decode(meta, n, step, C)
    du, dv, mask = angular_grid(meta, plan.n, plan.step)
    k0, frac, l = plan.k0, plan.frac, plan.l
    T, S = k0.shape
    n_v, n_u = len(dv), len(du)
    progress.stage("decoding %d x %d lenses (%s grid), %d x %d angular samples %.3g px apart (%s)"
                   % (S, T, meta.grid, n_u, n_v, plan.step,
                      "%.3g MiB" % (plan.nbytes / 1024.0 ** 2) if plan.nbytes < 1024 ** 3 else _gib(plan.nbytes)))
    data = np.zeros((T, S, n_v, n_u, C), np.float32)
    # A few angular rows at a time: the interpolation's temporaries stay small beside L.
    rows_per_chunk = max(1, (1 << 18) // max(S * n_u, 1))
    # Each microimage is sampled around its own centre: the metadata lattice where it is exact,
    # the measured centre behind a traced prescription (microimages.py). A lens that gets no light
    # (dark in the measured centres) gives zeros, and its grid points are marked in `dark`.
    dark = np.zeros((T, S), bool)
    for t in range(T):
        u0, v0, dark0 = microimage_centre(meta, k0[t], l[t])
        u1, v1, dark1 = microimage_centre(meta, k0[t] + 1, l[t])
        weight_next = frac[t][:, None, None, None]
        shifted = bool(np.any(frac[t] > 0))
        dark[t] = dark0 | ((frac[t] > 0) & dark1)
        for iv0 in range(0, n_v, rows_per_chunk):
            offset_v, offset_u = np.meshgrid(dv[iv0:iv0 + rows_per_chunk], du, indexing="ij")
            x0 = u0[:, None, None] + offset_u[None]
            y0 = v0[:, None, None] + offset_v[None]
            chunk = bilinear(raw, x0, y0) * (1 - weight_next)
            if shifted:
                x1 = u1[:, None, None] + offset_u[None]
                y1 = v1[:, None, None] + offset_v[None]
                chunk += bilinear(raw, x1, y1) * weight_next
            data[t, :, iv0:iv0 + rows_per_chunk] = chunk
        data[t, dark[t]] = 0
        progress.update(t + 1, T)
    if dark.any():
        progress.stage("%d of the %d lens positions get no light (dark in the measured microimage centres): "
                       "left black" % (int(dark.sum()), T * S))
    lf = LightField(data, du, dv, mask, plan.A, plan.R, plan.origin_st, meta, plan.step)
    lf.dark = dark
    return lf


def mosaic(lf: LightField, gap: int = 2) -> np.ndarray:
    """All views of LightField lf side by side, v down, u across; unusable angular samples left
    black."""
    T, S, n_v, n_u, C = lf.data.shape
    out = np.zeros((n_v * (T + gap) - gap, n_u * (S + gap) - gap, C), np.float32)
    for iv in range(n_v):
        for iu in range(n_u):
            if lf.mask[iv, iu]:
                out[iv * (T + gap):iv * (T + gap) + T, iu * (S + gap):iu * (S + gap) + S] = lf.view(iv, iu)
    return out
