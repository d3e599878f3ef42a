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

import math

import numpy as np

from .errors import DecodeError, MetadataError
from .images import bilinear
from .progress import Progress


class LightField:
    """A decoded light field and the geometry needed to use it.

    data:     float32 L[t, s, v, u, c]
    du, dv:   angular offsets of the u and v samples, pixels from the microimage centre
    mask:     bool [v, u], True where the offset lies inside the usable microimage disc
    A, R:     pixel vectors between neighbouring (s) and (t) grid positions on the sensor
    position: (s, t) -> raw pixel of that grid point: origin + (s0 + s) A + (t0 + t) R
    """

    def __init__(self, data, du, dv, mask, A, R, origin_st, meta, step):
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

    @property
    def shape(self):
        return self.data.shape

    def centre_index(self):
        return len(self.dv) // 2, len(self.du) // 2

    def view(self, iv, iu):
        """Sub-aperture view (T, S, C) at angular sample (iv, iu)."""
        return self.data[:, :, iv, iu, :]

    def grid_position(self, s, t):
        """Raw-image pixel position of grid point (s, t) (indices into data)."""
        s0, t0 = self.origin_st
        s = (s0 + np.asarray(s, float))[..., None]
        t = (t0 + np.asarray(t, float))[..., None]
        return self.meta.origin + s * self.A + t * self.R

    def kappa(self, slope):
        """Refocus slope (lenses along s per angular step) -> microimage-centre pixels per pixel."""
        return slope * np.hypot(*self.A) / self.step

    def slope_from_kappa(self, kappa):
        return kappa * self.step / np.hypot(*self.A)

    def shift_for(self, slope, iv, iu):
        """(ds, dt) grid shift of view (iv, iu) that aligns a point with this slope."""
        kappa = self.kappa(slope)
        ds, dt = self.M_inv @ (kappa * np.array([self.du[iu], self.dv[iv]]))
        return ds, dt

    def refocus(self, slope):
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

    def epi(self, t, iv=None):
        """Horizontal epipolar-plane image at lens row t and angular row iv (default centre):
        array (n_u, S, C), u down, s across, only the usable u samples; and the list of those
        u sample indices."""
        if iv is None:
            iv = len(self.dv) // 2
        usable_u = [iu for iu in range(len(self.du)) if self.mask[iv, iu]]
        return np.stack([self.data[t, :, iv, iu, :] for iu in usable_u], axis=0), usable_u

    def slope_to_distance(self, slope):
        return self.meta.slope_to_distance(self.kappa(slope))

    def display_aspect(self):
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


def angular_grid(meta, n=None, step=1.0):
    """Offsets (pixels) of the angular samples and the usable-disc mask: (du, dv, mask).

    The usable radius is the smaller of the main-aperture disc (microimage_diameter_px / 2) and
    the microimage cell's inradius, less one pixel so that every sample is fully lit.
    n (odd) overrides the count."""
    # Inradius of a microimage cell: half the distance to the nearest neighbouring centre.
    if meta.grid == "rectangular":
        radius = 0.5 * min(np.hypot(*meta.a), np.hypot(*meta.b))
    else:
        radius = 0.5 * np.hypot(*meta.a)
    if meta.diameter_px is not None and meta.diameter_px > 0:
        radius = min(radius, 0.5 * meta.diameter_px)
    usable = radius - 1.0
    if n is None:
        half = max(int(math.floor(usable / step + 1e-9)), 0)
        n = 2 * half + 1
    if n < 1 or n % 2 == 0:
        raise DecodeError("the angular sample count must be odd and positive, got %d" % n)
    offsets = (np.arange(n) - n // 2) * float(step)
    dv, du = np.meshgrid(offsets, offsets, indexing="ij")
    mask = np.hypot(du, dv) <= max(usable, 0.0) + 1e-9
    mask[n // 2, n // 2] = True
    return offsets.copy(), offsets.copy(), mask


def decode(raw, meta, n=None, step=1.0, progress=None):
    """Raw image (H, W, C float) + Metadata -> LightField.

    n: angular samples per axis (odd; default as many `step`-pixel steps as fit the usable
    microimage disc); progress: a Progress for stage messages (default silent)."""
    if progress is None:
        progress = Progress(False)
    H, W = raw.shape[:2]
    if (W, H) != (meta.width, meta.height):
        raise MetadataError("fields 'image.width' x 'image.height' are %d x %d but the raw image is %d x %d"
                            % (meta.width, meta.height, W, H))
    du, dv, mask = angular_grid(meta, n, step)
    A, R, sa, rho, h = _rectangular_grid_axes(meta)
    grid_inverse = np.linalg.inv(np.column_stack([A, R]))
    corners = np.array([[0, 0], [W - 1, 0], [0, H - 1], [W - 1, H - 1]], float) - meta.origin
    corners_st = corners @ grid_inverse.T
    if not (np.isfinite(corners_st).all() and np.ptp(corners_st[:, 0]) * np.ptp(corners_st[:, 1]) <= 4.0 * W * H):
        raise DecodeError("the metadata lattice puts no sensible grid of microimages on the %d x %d image" % (W, H))
    s_all = np.arange(math.floor(corners_st[:, 0].min()) - 1, math.ceil(corners_st[:, 0].max()) + 2)
    t_all = np.arange(math.floor(corners_st[:, 1].min()) - 1, math.ceil(corners_st[:, 1].max()) + 2)
    ss, tt = np.meshgrid(s_all, t_all)
    # Skew index of every grid point: lens (k0, l) and, for a hexagonal half-shifted row, the
    # fraction `frac` of the way to lens (k0 + 1, l).
    k = ss * sa - tt * rho * h
    l = tt * rho
    k0 = np.floor(k + 1e-9)
    frac = k - k0
    reach_u = np.abs(du[np.any(mask, axis=0)]).max()
    reach_v = np.abs(dv[np.any(mask, axis=1)]).max()

    def inside(kk, ll):
        u, v = meta.centre(kk, ll)
        return (u - reach_u >= 0) & (u + reach_u <= W - 1) & (v - reach_v >= 0) & (v + reach_v <= H - 1)

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
    k0, frac, l = k0[kept], frac[kept].astype(np.float32), l[kept]
    T, S = k0.shape
    n_v, n_u = len(dv), len(du)
    C = raw.shape[2]
    progress.stage("decoding %d x %d lenses (%s grid), %d x %d angular samples %.3g px apart"
                   % (S, T, meta.grid, n_u, n_v, step))
    data = np.zeros((T, S, n_v, n_u, C), np.float32)
    offset_v, offset_u = np.meshgrid(dv, du, indexing="ij")
    for t in range(T):
        u0, v0 = meta.centre(k0[t], l[t])
        u1, v1 = meta.centre(k0[t] + 1, l[t])
        x0 = u0[:, None, None] + offset_u[None]
        y0 = v0[:, None, None] + offset_v[None]
        x1 = u1[:, None, None] + offset_u[None]
        y1 = v1[:, None, None] + offset_v[None]
        weight_next = frac[t][:, None, None, None]
        row = bilinear(raw, x0, y0) * (1 - weight_next)
        if np.any(frac[t] > 0):
            row += bilinear(raw, x1, y1) * weight_next
        data[t] = row
        progress.update(t + 1, T)
    return LightField(data, du, dv, mask, A, R, (s_all[s_lo], t_all[t_lo]), meta, float(step))


def mosaic(lf, gap=2):
    """All views of LightField lf side by side, v down, u across; unusable angular samples left
    black."""
    T, S, n_v, n_u, C = lf.data.shape
    out = np.zeros((n_v * (T + gap) - gap, n_u * (S + gap) - gap, C), np.float32)
    for iv in range(n_v):
        for iu in range(n_u):
            if lf.mask[iv, iu]:
                out[iv * (T + gap):iv * (T + gap) + T, iu * (S + gap):iu * (S + gap) + S] = lf.view(iv, iu)
    return out
