# SPDX-License-Identifier: AGPL-3.0-or-later
"""Light fields from raw plenoptic renders: the library behind tools/plenoptic-decode.

A plenoptic render (camera { plenoptic ... }) writes a raw lenslet image and, beside it,
<stem>.plenoptic.json (docs/metadata.md) with the microimage-centre lattice. This module
samples every microimage on a regular grid of (u, v) offsets around its centre and arranges
the samples as a 4-D light field

    L[t, s, v, u, c]     t, s: lens row and column (a rectangular grid, row t top to bottom,
                               column s left to right, as the picture shows them)
                         v, u: angular sample, offset (dv, du) pixels from the microimage
                               centre (u to the right, v downwards, as in the raw image)
                         c:    colour channel (R, G, B), linear light

Hexagonal lattices are resampled to the rectangular (s, t) grid: every other lens row sits
half a lens to the side, so its values are interpolated linearly between its two neighbours
in that row. Sub-aperture views, refocusing by shift-and-add and epipolar-plane images are
computed from L. Only numpy and Pillow (and OpenImageIO for EXR/16-bit input) are used.

Conventions (docs/metadata.md): pixel coordinates are continuous, 0-based, the centre of pixel
(column i, row j) at (i, j). Lens indices in the metadata lattice are skew indices:
centre(k, l) = origin + k a + l b.
"""

import json
import math
import os
import subprocess
import sys
import time

import numpy as np

METADATA_FORMAT = "povray-plenoptic-metadata"
METADATA_VERSION = 1


class MetadataError(Exception):
    """The metadata file is missing, unreadable, not JSON, or lacks / garbles a field."""


class DecodeError(Exception):
    """The raw image cannot be decoded with this metadata (size mismatch, no lens inside...)."""


# --------------------------------------------------------------------------------------------
# Metadata

def _field(data, path):
    """The value at a dotted path, or MetadataError naming the first missing part."""
    node = data
    walked = []
    for part in path.split("."):
        walked.append(part)
        if not isinstance(node, dict) or part not in node:
            raise MetadataError("field '%s' is missing" % ".".join(walked))
        node = node[part]
    return node


def _describe(value):
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "the number %r" % value
    if isinstance(value, str):
        return "the string %r" % value
    if isinstance(value, list):
        return "an array of %d items" % len(value)
    return "an object"


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _number(data, path, positive=False):
    value = _field(data, path)
    if not _is_number(value) or (positive and not value > 0):
        raise MetadataError("field '%s' must be a %s number, found %s"
                            % (path, "positive" if positive else "finite", _describe(value)))
    return float(value)


def _numbers(data, path, count, positive=False):
    value = _field(data, path)
    if not isinstance(value, list) or len(value) != count:
        raise MetadataError("field '%s' must be an array of %d numbers, found %s"
                            % (path, count, _describe(value)))
    for i, item in enumerate(value):
        if not _is_number(item) or (positive and not item > 0):
            raise MetadataError("field '%s[%d]' must be a %s number, found %s"
                                % (path, i, "positive" if positive else "finite", _describe(item)))
    return np.array(value, dtype=float)


def _optional_number(data, path):
    try:
        value = _field(data, path)
    except MetadataError:
        return None
    return float(value) if _is_number(value) else None


class Metadata:
    """The fields of a render's metadata that decoding needs, checked.

    Attributes: path, raw (the parsed JSON), width, height, origin, a, b (numpy 2-vectors,
    pixels), grid ('hexagonal' | 'rectangular'), diameter_px (or None), pixel_size_mm,
    and the optics (main lens and array distances) when present, for depth labels.
    """

    def __init__(self, raw, path="<metadata>"):
        self.path = path
        self.raw = raw
        if not isinstance(raw, dict):
            raise MetadataError("the file must hold a JSON object, found %s" % _describe(raw))
        fmt = _field(raw, "format")
        if fmt != METADATA_FORMAT:
            raise MetadataError("field 'format' must be %r, found %s" % (METADATA_FORMAT, _describe(fmt)))
        version = _field(raw, "version")
        if version != METADATA_VERSION or isinstance(version, bool):
            raise MetadataError("field 'version' must be %d (the version this tool reads), found %s"
                                % (METADATA_VERSION, _describe(version)))
        for key in ("width", "height"):
            value = _field(raw, "image." + key)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise MetadataError("field 'image.%s' must be a positive whole number, found %s"
                                    % (key, _describe(value)))
        self.width = int(raw["image"]["width"])
        self.height = int(raw["image"]["height"])
        self.pixel_size_mm = _numbers(raw, "sensor.pixel_size_mm", 2, positive=True)

        array = _field(raw, "microlens_array")
        lattice = _field(raw, "microimage_lattice")
        if array is None or lattice is None:
            raise MetadataError("fields 'microlens_array' and 'microimage_lattice' are null: the render has "
                                "no microlens array, so there is no light field to decode")
        if not isinstance(array, dict):
            raise MetadataError("field 'microlens_array' must be an object, found %s" % _describe(array))
        if not isinstance(lattice, dict):
            raise MetadataError("field 'microimage_lattice' must be an object, found %s" % _describe(lattice))
        grid = _field(raw, "microlens_array.grid")
        if grid not in ("hexagonal", "rectangular"):
            raise MetadataError("field 'microlens_array.grid' must be \"hexagonal\" or \"rectangular\", found %s"
                                % _describe(grid))
        self.grid = grid
        self.origin = _numbers(raw, "microimage_lattice.origin_px", 2)
        basis = _field(raw, "microimage_lattice.basis_px")
        if (not isinstance(basis, list) or len(basis) != 2
                or not all(isinstance(v, list) and len(v) == 2 and all(_is_number(x) for x in v) for v in basis)):
            raise MetadataError("field 'microimage_lattice.basis_px' must be two pairs of finite numbers "
                                "[[ax, ay], [bx, by]], found %s" % _describe(basis))
        self.a = np.array(basis[0], dtype=float)
        self.b = np.array(basis[1], dtype=float)
        det = self.a[0] * self.b[1] - self.a[1] * self.b[0]
        if (not abs(det) > 0.1 * (np.hypot(*self.a) * np.hypot(*self.b))
                or min(np.hypot(*self.a), np.hypot(*self.b)) < 1.0):
            raise MetadataError("field 'microimage_lattice.basis_px' must hold two independent vectors of at "
                                "least a pixel, found %r" % (basis,))
        self.diameter_px = _optional_number(raw, "microimage_lattice.microimage_diameter_px")

        # The optics, for the refocus sweep's depth labels: checked like the rest, since a wrong
        # value here means a wrong file.
        self.mm_per_unit = _number(raw, "mm_per_unit", positive=True)
        self.main_lens_type = _field(raw, "main_lens.type")
        if self.main_lens_type not in ("thin_lens", "pinhole", "none"):
            raise MetadataError("field 'main_lens.type' must be \"thin_lens\", \"pinhole\" or \"none\", found %s"
                                % _describe(self.main_lens_type))
        self.focal_length_mm = None
        main_distance = 0.0
        if self.main_lens_type == "thin_lens":
            self.focal_length_mm = _number(raw, "main_lens.focal_length_mm", positive=True)
            _number(raw, "main_lens.aperture_mm", positive=True)
        if self.main_lens_type != "none":
            main_distance = _number(raw, "main_lens.distance_mm", positive=True)
        self.pitch_mm = _number(raw, "microlens_array.pitch_mm", positive=True)
        array_distance = _number(raw, "microlens_array.distance_mm", positive=True)
        tz = _numbers(raw, "microlens_array.translate_mm", 3)[2]
        # Distances at the array centre, including the array's z translation.
        self.main_distance_mm = main_distance - tz
        self.array_distance_mm = array_distance + tz

    def centre(self, k, l):
        """Microimage centre(s) of skew lens index (k, l), pixels."""
        k = np.asarray(k, dtype=float)
        l = np.asarray(l, dtype=float)
        return (self.origin[0] + k * self.a[0] + l * self.b[0],
                self.origin[1] + k * self.a[1] + l * self.b[1])

    def all_centres(self, margin=0.0):
        """Skew indices and centres of every microimage whose centre lies inside the image,
        at least `margin` pixels from its border: (k, l, u, v) arrays."""
        m = np.column_stack([self.a, self.b])
        inv = np.linalg.inv(m)
        corners = np.array([[0, 0], [self.width - 1, 0], [0, self.height - 1],
                            [self.width - 1, self.height - 1]], dtype=float) - self.origin
        kl = corners @ inv.T
        k_range = np.arange(math.floor(kl[:, 0].min()) - 1, math.ceil(kl[:, 0].max()) + 2)
        l_range = np.arange(math.floor(kl[:, 1].min()) - 1, math.ceil(kl[:, 1].max()) + 2)
        kk, ll = np.meshgrid(k_range, l_range)
        u, v = self.centre(kk, ll)
        keep = ((u >= margin) & (u <= self.width - 1 - margin) & (v >= margin) & (v <= self.height - 1 - margin))
        return kk[keep], ll[keep], u[keep], v[keep]

    def slope_to_distance(self, kappa):
        """Scene distance (in front of the main lens, scene units) in focus for a refocus shift of
        kappa microimage-centre pixels per pixel of angular offset, from the thin-lens equations
        with the chief-ray geometry of plenoptic 1.0; inf beyond infinity; None when the
        metadata has no thin main lens."""
        if self.main_lens_type != "thin_lens":
            return None
        D, d, F = self.main_distance_mm, self.array_distance_mm, self.focal_length_mm
        denominator = 1.0 + kappa * d / (D + d)
        if denominator <= 0:
            return math.inf
        b = D / denominator  # where the main lens images the plane in focus
        if b <= F:
            return math.inf
        return b * F / (b - F) / self.mm_per_unit


def load_metadata(path, image_size=None):
    """Reads and checks a metadata file; image_size (width, height) is compared with it.
    Raises MetadataError with one sentence naming the file's problem."""
    try:
        with open(path, "rb") as f:
            text = f.read()
    except OSError as e:
        raise MetadataError("cannot read the metadata file: %s" % (e.strerror or e))
    try:
        raw = json.loads(text.decode("utf-8"))
    except UnicodeDecodeError as e:
        raise MetadataError("not valid JSON: not UTF-8 text (%s)" % e.reason)
    except ValueError as e:
        raise MetadataError("not valid JSON: %s" % e)
    meta = Metadata(raw, path)
    if image_size is not None and (meta.width, meta.height) != tuple(image_size):
        raise MetadataError("fields 'image.width' x 'image.height' are %d x %d but the raw image is %d x %d: "
                            "this metadata belongs to another render"
                            % (meta.width, meta.height, image_size[0], image_size[1]))
    return meta


def metadata_path_for(image_path):
    """<dir>/<stem>.plenoptic.json for <dir>/<stem>.<ext>, as the renderer names it."""
    stem, _ = os.path.splitext(image_path)
    return stem + ".plenoptic.json"


# --------------------------------------------------------------------------------------------
# Images

def srgb_to_linear(x):
    x = np.asarray(x, dtype=np.float32)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(x):
    x = np.clip(np.asarray(x, dtype=np.float32), 0.0, 1.0)
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055).astype(np.float32)


def read_raw(path, encoding="auto"):
    """The raw image as float32 (H, W, 3), linear light.

    encoding: 'auto' (sRGB for 8/16-bit files, linear for float files such as EXR),
    'srgb', 'linear', or a number (a pure power-law gamma). Raises DecodeError."""
    data = None
    is_float = False
    try:
        import OpenImageIO as oiio  # noqa: N813 (Debian's python3-openimageio)
        buf = oiio.ImageBuf(path)
        spec = buf.spec()
        if buf.has_error or spec.width == 0:
            raise DecodeError("cannot read raw image %s: %s" % (path, buf.geterror().strip() or "unknown format"))
        is_float = spec.format.basetype in (oiio.FLOAT, oiio.HALF, oiio.DOUBLE)
        data = np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32)
    except ImportError:
        try:
            from PIL import Image
            with Image.open(path) as im:
                mode = im.mode
                arr = np.asarray(im.convert("RGB") if mode not in ("I;16", "I", "F") else im)
            if arr.dtype == np.uint8:
                data = arr.astype(np.float32) / 255.0
            elif mode == "F":
                data = arr.astype(np.float32)
                is_float = True
            else:
                data = arr.astype(np.float32) / 65535.0
        except OSError as e:
            raise DecodeError("cannot read raw image %s: %s" % (path, e))
    if data.ndim == 2:
        data = data[:, :, None]
    if data.shape[2] == 1:
        data = np.repeat(data, 3, axis=2)
    elif data.shape[2] == 2:  # grey + alpha
        data = np.repeat(data[:, :, :1], 3, axis=2)
    data = data[:, :, :3]
    if encoding == "auto":
        encoding = "linear" if is_float else "srgb"
    if encoding == "srgb":
        data = srgb_to_linear(data)
    elif encoding != "linear":
        data = np.power(np.clip(data, 0, None), float(encoding)).astype(np.float32)
    return np.ascontiguousarray(data, dtype=np.float32)


def to_8bit(image):
    """Linear float image -> 8-bit sRGB array."""
    return (linear_to_srgb(image) * 255.0 + 0.5).astype(np.uint8)


def save_png(path, image):
    from PIL import Image
    arr = to_8bit(image)
    if arr.ndim == 3 and arr.shape[2] == 1:
        arr = arr[:, :, 0]
    Image.fromarray(arr).save(path)


def bilinear(image, x, y):
    """Samples image (H, W, C) at continuous pixel positions x, y (centre convention), clamped
    to the image; result has shape x.shape + (C,)."""
    h, w = image.shape[:2]
    x = np.clip(np.asarray(x, dtype=np.float64), 0, w - 1)
    y = np.clip(np.asarray(y, dtype=np.float64), 0, h - 1)
    x0 = np.minimum(np.floor(x).astype(np.intp), max(w - 2, 0))
    y0 = np.minimum(np.floor(y).astype(np.intp), max(h - 2, 0))
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    fx = (x - x0)[..., None].astype(np.float32)
    fy = (y - y0)[..., None].astype(np.float32)
    return ((image[y0, x0] * (1 - fx) + image[y0, x1] * fx) * (1 - fy)
            + (image[y1, x0] * (1 - fx) + image[y1, x1] * fx) * fy)


# --------------------------------------------------------------------------------------------
# Progress

class Progress:
    """Stage messages and, for stages longer than a second, percentages on stderr."""

    def __init__(self, enabled=True, prefix="plenoptic-decode"):
        self.enabled = enabled
        self.prefix = prefix
        self._label = None
        self._start = 0.0
        self._last = 0.0

    def stage(self, label):
        self._label = label
        self._start = self._last = time.monotonic()
        if self.enabled:
            print("%s: %s" % (self.prefix, label), file=sys.stderr, flush=True)

    def update(self, done, total):
        if not self.enabled or total <= 0:
            return
        now = time.monotonic()
        if now - self._start > 1.0 and (now - self._last > 1.0 or done == total):
            self._last = now
            print("%s:   %s %d%%" % (self.prefix, self._label, int(100 * done / total)), file=sys.stderr, flush=True)


# --------------------------------------------------------------------------------------------
# Light field

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
        k = self.kappa(slope)
        ds, dt = self.M_inv @ (k * np.array([self.du[iu], self.dv[iv]]))
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
        array (n_u, S, C), u down, s across, only the usable u samples."""
        if iv is None:
            iv = len(self.dv) // 2
        cols = [iu for iu in range(len(self.du)) if self.mask[iv, iu]]
        return np.stack([self.data[t, :, iv, iu, :] for iu in cols], axis=0), cols

    def slope_to_distance(self, slope):
        return self.meta.slope_to_distance(self.kappa(slope))

    def display_aspect(self):
        """Height/width of one (s, t) grid cell on the sensor (sqrt(3)/2 for hexagonal grids)."""
        return np.hypot(*self.R) / np.hypot(*self.A)


def _grid_axes(meta):
    """Row vectors of the rectangular lens grid: A along the lens rows pointing right in the
    image, R from one row to the next pointing down; and the skew coefficients so that
    origin + s A + t R = origin + (s*sa - t*rho*h) a + (t*rho) b."""
    a = meta.a
    h = 0.5 if meta.grid == "hexagonal" else 0.0
    sa = 1.0 if (a[0] > 0 or (a[0] == 0 and a[1] > 0)) else -1.0
    r = meta.b - h * a
    rho = 1.0 if r[1] >= 0 else -1.0
    return sa * a, rho * r, sa, rho, h


def angular_grid(meta, n=None, step=1.0):
    """Offsets (pixels) of the angular samples and the usable-disc mask.

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
    """Raw image (H, W, C float) + Metadata -> LightField."""
    if progress is None:
        progress = Progress(False)
    H, W = raw.shape[:2]
    if (W, H) != (meta.width, meta.height):
        raise MetadataError("fields 'image.width' x 'image.height' are %d x %d but the raw image is %d x %d"
                            % (meta.width, meta.height, W, H))
    du, dv, mask = angular_grid(meta, n, step)
    A, R, sa, rho, h = _grid_axes(meta)
    M = np.column_stack([A, R])
    inv = np.linalg.inv(M)
    corners = np.array([[0, 0], [W - 1, 0], [0, H - 1], [W - 1, H - 1]], float) - meta.origin
    st = corners @ inv.T
    if not (np.isfinite(st).all() and np.ptp(st[:, 0]) * np.ptp(st[:, 1]) <= 4.0 * W * H):
        raise DecodeError("the metadata lattice puts no sensible grid of microimages on the %d x %d image" % (W, H))
    s_all = np.arange(math.floor(st[:, 0].min()) - 1, math.ceil(st[:, 0].max()) + 2)
    t_all = np.arange(math.floor(st[:, 1].min()) - 1, math.ceil(st[:, 1].max()) + 2)
    ss, tt = np.meshgrid(s_all, t_all)
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
        sub = ~valid[t_lo:t_hi + 1, s_lo:s_hi + 1]
        losses = [sub[0].mean(), sub[-1].mean(), sub[:, 0].mean(), sub[:, -1].mean()]
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
    sel = (slice(t_lo, t_hi + 1), slice(s_lo, s_hi + 1))
    k0, frac, l = k0[sel], frac[sel].astype(np.float32), l[sel]
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
        f = frac[t][:, None, None, None]
        row = bilinear(raw, x0, y0) * (1 - f)
        if np.any(frac[t] > 0):
            row += bilinear(raw, x1, y1) * f
        data[t] = row
        progress.update(t + 1, T)
    return LightField(data, du, dv, mask, A, R, (s_all[s_lo], t_all[t_lo]), meta, float(step))


# --------------------------------------------------------------------------------------------
# Measures used by the decoder and by the tests

def gray(image):
    image = np.asarray(image, dtype=np.float64)
    if image.ndim == 3:
        return image[..., :3].mean(axis=-1)
    return image


def box3(x):
    """3 x 3 box mean with edge replication."""
    p = np.pad(x, 1, mode="edge")
    return sum(p[i:i + x.shape[0], j:j + x.shape[1]] for i in range(3) for j in range(3)) / 9.0


def laplacian_energy(image):
    """Per-pixel squared Laplacian of the grey image, 3 x 3 box-smoothed (a focus measure)."""
    g = gray(image)
    p = np.pad(g, 1, mode="edge")
    lap = p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:] - 4 * g
    return box3(lap * lap)


def default_slopes(lf, count=9, reach_lenses=2.0):
    """Slopes that shift the outermost usable views by -reach..+reach lenses."""
    half = max(np.abs(lf.du[np.any(lf.mask, axis=0)]).max() / lf.step, 1.0)
    limit = reach_lenses / half
    return np.linspace(-limit, limit, count)


def distance_to_slope(lf, distance):
    """Inverse of LightField.slope_to_distance (thin main lens only; None otherwise)."""
    meta = lf.meta
    if meta.main_lens_type != "thin_lens":
        return None
    z = distance * meta.mm_per_unit
    F, D, d = meta.focal_length_mm, meta.main_distance_mm, meta.array_distance_mm
    if not z > F:
        return None
    b = z * F / (z - F)
    return lf.slope_from_kappa((D / b - 1) * (D + d) / d)


def slopes_from_depth_map(lf, count=9):
    """A sweep covering the scene's depths, when the render wrote a depth map (metadata field
    'depth_map', beside the metadata file) and the main lens is thin: from the 2nd to the 98th
    percentile of the finite depths, widened by a quarter of the span on each side and always
    including slope 0. None when there is no usable depth map."""
    name = lf.meta.raw.get("depth_map")
    if not isinstance(name, str) or lf.meta.main_lens_type != "thin_lens":
        return None
    path = os.path.join(os.path.dirname(os.path.abspath(lf.meta.path)), name)
    try:
        import OpenImageIO as oiio
        buf = oiio.ImageBuf(path)
        if buf.has_error:
            return None
        depth = np.asarray(buf.get_pixels(oiio.FLOAT))[..., 0]
    except (ImportError, OSError):
        return None
    finite = depth[np.isfinite(depth) & (depth > 0)]
    if finite.size < 10:
        return None
    ends = [distance_to_slope(lf, z) for z in np.percentile(finite, [2, 98])]
    if any(e is None for e in ends):
        return None
    lo, hi = min(ends + [0.0]), max(ends + [0.0])
    widen = max(0.25 * (hi - lo), 1e-3)
    return np.linspace(lo - widen, hi + widen, count)


def sharpest_slope_map(images):
    """Per pixel: index of the refocused image with the highest focus measure, and that measure."""
    energies = np.stack([laplacian_energy(im) for im in images])
    return np.argmax(energies, axis=0), energies.max(axis=0)


def pick_near_far(slopes, best, strength):
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


def pick_epi_row(lf, best, strength):
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


# --------------------------------------------------------------------------------------------
# Forward projection through the compiled tool

def find_project_tool():
    """Path of plenoptic-project: $PLENOPTIC_PROJECT, beside this file, or on PATH."""
    env = os.environ.get("PLENOPTIC_PROJECT")
    if env:
        return env
    here = os.path.dirname(os.path.abspath(__file__))
    for candidate in (os.path.join(here, "plenoptic-project"),):
        if os.access(candidate, os.X_OK):
            return candidate
    return "plenoptic-project"


def project_points(metadata_path, points, tool=None):
    """World points (scene units, N x 3) -> list of (point_index, lens_k, lens_l, u, v), one per
    image of each point, by running plenoptic-project. Raises RuntimeError with its message."""
    tool = tool or find_project_tool()
    text = "\n".join("%.17g %.17g %.17g" % tuple(p) for p in points) + "\n"
    run = subprocess.run([tool, metadata_path, "-"], input=text, capture_output=True, text=True)
    if run.returncode != 0:
        raise RuntimeError(run.stderr.strip() or "plenoptic-project failed with status %d" % run.returncode)
    hits = []
    for line in run.stdout.splitlines():
        i, k, l, u, v = line.split()
        hits.append((int(i), int(k), int(l), float(u), float(v)))
    return hits


# --------------------------------------------------------------------------------------------
# Pictures

def _font(size):
    from PIL import ImageFont
    for path in ("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                 "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf"):
        if os.path.exists(path):
            try:
                return ImageFont.truetype(path, size)
            except OSError:
                pass
    return ImageFont.load_default()


def _to_pil(image, width=None, height=None, aspect=1.0):
    """Linear image -> PIL image scaled (nearest neighbour: every lens stays a visible cell) to
    fit width x height, with rows stretched by `aspect` (cell height / width)."""
    from PIL import Image
    im = Image.fromarray(to_8bit(image))
    w, h = im.size
    h_eff = h * aspect
    scale = min(width / w if width else 1e9, height / h_eff if height else 1e9)
    size = (max(1, int(round(w * scale))), max(1, int(round(h_eff * scale))))
    return im.resize(size, Image.NEAREST)


def _fmt_distance(distance):
    if distance is None:
        return ""
    if math.isinf(distance):
        return "  (~ infinity)"
    return "  (~%.3g units)" % distance


def mosaic(lf, gap=2):
    """All views side by side, v down, u across; unusable angular samples left black."""
    T, S, n_v, n_u, C = lf.data.shape
    out = np.zeros((n_v * (T + gap) - gap, n_u * (S + gap) - gap, C), np.float32)
    for iv in range(n_v):
        for iu in range(n_u):
            if lf.mask[iv, iu]:
                out[iv * (T + gap):iv * (T + gap) + T, iu * (S + gap):iu * (S + gap) + S] = lf.view(iv, iu)
    return out


def contact_sheet(raw, lf, slopes, refocused, near, far, epi_row, title=""):
    """One picture that shows the plenoptic effect: raw crop with the metadata lattice, centre
    view, views from opposite sides of the aperture, an EPI, near and far refocus."""
    from PIL import Image, ImageDraw
    meta = lf.meta
    panel_w, panel_h, pad = 300, 225, 12
    title_font, label_font, small_font = _font(18), _font(14), _font(11)
    panels = []

    # 1. Raw crop around the image centre, about five microimages across, lattice centres marked.
    pitch = np.hypot(*meta.a)
    H, W = raw.shape[:2]
    cw = int(min(W, max(16, round(5.5 * pitch))))
    ch = int(min(H, max(12, round(cw * panel_h / panel_w))))
    x0, y0 = (W - cw) // 2, (H - ch) // 2
    crop = raw[y0:y0 + ch, x0:x0 + cw]
    im = _to_pil(crop, panel_w, panel_h)
    scale = im.size[0] / cw
    draw = ImageDraw.Draw(im)
    k, l, u, v = meta.all_centres()
    for uu, vv in zip(u, v):
        if x0 - 0.5 <= uu <= x0 + cw - 0.5 and y0 - 0.5 <= vv <= y0 + ch - 0.5:
            px, py = (uu - x0 + 0.5) * scale, (vv - y0 + 0.5) * scale
            draw.line([(px - 3, py), (px + 3, py)], fill=(255, 60, 60))
            draw.line([(px, py - 3), (px, py + 3)], fill=(255, 60, 60))
    panels.append((im, "Raw lenslet image (crop)", "%d x %d px; + = microimage centres (metadata)" % (cw, ch)))

    aspect = lf.display_aspect()
    cv, cu = lf.centre_index()
    panels.append((_to_pil(lf.view(cv, cu), panel_w, panel_h, aspect), "Centre view",
                   "%d x %d lenses, one pixel per lens" % (lf.shape[1], lf.shape[0])))
    usable = [iu for iu in range(len(lf.du)) if lf.mask[cv, iu]]
    left, right = usable[0], usable[-1]
    panels.append((_to_pil(lf.view(cv, left), panel_w, panel_h, aspect), "View from the aperture's left",
                   "u offset %+.3g px" % lf.du[left]))
    panels.append((_to_pil(lf.view(cv, right), panel_w, panel_h, aspect), "View from the aperture's right",
                   "u offset %+.3g px (compare with the left view)" % lf.du[right]))

    # EPI, stretched to fill its (double-width) panel: a tilted streak is a point off the focus plane.
    epi, cols = lf.epi(epi_row, cv)
    epi_im = Image.fromarray(to_8bit(epi)).resize((2 * panel_w + pad, panel_h), Image.NEAREST)
    panels.append((epi_im, "Epipolar-plane image (lens row %d of the views)" % epi_row,
                   "across: lens s; down: view u %+.3g..%+.3g px; vertical = in focus, tilt = nearer or farther"
                   % (lf.du[cols[0]], lf.du[cols[-1]])))
    for name, idx in (("Refocused near", near), ("Refocused far", far)):
        dist = lf.slope_to_distance(slopes[idx])
        panels.append((_to_pil(refocused[idx], panel_w, panel_h, aspect), name,
                       "slope %+.3f lens/view%s" % (slopes[idx], _fmt_distance(dist))))

    # Layout: first row 4 panels, second row EPI (double width) + 2 refocus.
    label_h, caption_h, head_h = 20, 16, 34 if title else 8
    cell_w, cell_h = panel_w + pad, panel_h + label_h + caption_h + pad
    sheet_w = 4 * cell_w + pad
    sheet_h = head_h + 2 * cell_h + pad
    sheet = Image.new("RGB", (sheet_w, sheet_h), (24, 24, 28))
    draw = ImageDraw.Draw(sheet)
    if title:
        draw.text((pad, 8), title, fill=(240, 240, 240), font=title_font)
    slots = [(0, 0, 1), (1, 0, 1), (2, 0, 1), (3, 0, 1), (0, 1, 2), (2, 1, 1), (3, 1, 1)]
    for (im, label, caption), (col, row, span) in zip(panels, slots):
        x = pad + col * cell_w
        y = head_h + row * cell_h
        draw.text((x, y), label, fill=(255, 255, 255), font=label_font)
        box_w = span * cell_w - pad
        ox = x + (box_w - im.size[0]) // 2
        oy = y + label_h + (panel_h - im.size[1]) // 2
        draw.rectangle([x - 1, y + label_h - 1, x + box_w, y + label_h + panel_h], outline=(70, 70, 80))
        sheet.paste(im, (ox, oy))
        draw.text((x, y + label_h + panel_h + 3), caption, fill=(190, 190, 200), font=small_font)
    return sheet


# --------------------------------------------------------------------------------------------
# Command line

def parse_slopes(text):
    parts = text.split(":")
    if len(parts) != 3:
        raise ValueError("--slopes takes LO:HI:COUNT, e.g. -0.5:0.5:11")
    lo, hi, count = float(parts[0]), float(parts[1]), int(parts[2])
    if count < 2 or not (math.isfinite(lo) and math.isfinite(hi)) or lo >= hi:
        raise ValueError("--slopes needs LO < HI and COUNT >= 2")
    return np.linspace(lo, hi, count)


def write_outputs(raw, lf, outdir, slopes, gif=True, npy=True, progress=None, title=""):
    """Writes views, mosaic, refocus sweep (+ GIF), EPI, contact sheet and a JSON description.
    Returns the path of the contact sheet."""
    from PIL import Image
    if progress is None:
        progress = Progress(False)
    os.makedirs(os.path.join(outdir, "views"), exist_ok=True)
    os.makedirs(os.path.join(outdir, "refocus"), exist_ok=True)
    T, S, n_v, n_u, _ = lf.shape
    aspect = lf.display_aspect()

    progress.stage("writing %d sub-aperture views" % int(lf.mask.sum()))
    names = []
    for iv in range(n_v):
        for iu in range(n_u):
            if lf.mask[iv, iu]:
                name = "view_v%+03d_u%+03d.png" % (int(round(lf.dv[iv] / lf.step)), int(round(lf.du[iu] / lf.step)))
                save_png(os.path.join(outdir, "views", name), lf.view(iv, iu))
                names.append(name)
    Image.fromarray(to_8bit(mosaic(lf))).save(os.path.join(outdir, "views_mosaic.png"))

    progress.stage("refocusing at %d slopes" % len(slopes))
    refocused = []
    frames = []
    for i, slope in enumerate(slopes):
        image = lf.refocus(slope)
        refocused.append(image)
        save_png(os.path.join(outdir, "refocus", "refocus_%02d_slope%+.4f.png" % (i, slope)), image)
        frames.append(_to_pil(image, 4 * S, None, aspect))
        progress.update(i + 1, len(slopes))
    if gif and len(frames) > 1:
        try:
            sequence = frames + frames[-2:0:-1]
            sequence[0].save(os.path.join(outdir, "refocus.gif"), save_all=True, append_images=sequence[1:],
                             duration=180, loop=0)
        except (OSError, ValueError) as e:  # Pillow without GIF support: the PNGs are there
            print("plenoptic-decode: no GIF written (%s)" % e, file=sys.stderr)

    progress.stage("drawing the EPI and the contact sheet")
    best, strength = sharpest_slope_map(refocused)
    near, far = pick_near_far(slopes, best, strength)
    epi_row = pick_epi_row(lf, best, strength)
    cv, _ = lf.centre_index()
    epi, cols = lf.epi(epi_row, cv)
    Image.fromarray(to_8bit(epi)).resize((S * 8, len(cols) * 16), Image.NEAREST).save(os.path.join(outdir, "epi.png"))
    sheet = contact_sheet(raw, lf, slopes, refocused, near, far, epi_row, title)
    sheet_path = os.path.join(outdir, "contact_sheet.png")
    sheet.save(sheet_path)

    if npy:
        np.save(os.path.join(outdir, "lightfield.npy"), lf.data)
    description = {
        "array": "lightfield.npy" if npy else None,
        "axes": "L[t, s, v, u, c]: lens row, lens column, angular row, angular column, colour (linear RGB)",
        "shape": list(lf.shape),
        "du_px": lf.du.tolist(),
        "dv_px": lf.dv.tolist(),
        "usable_mask": lf.mask.astype(int).tolist(),
        "grid_s_vector_px": lf.A.tolist(),
        "grid_t_vector_px": lf.R.tolist(),
        "grid_origin_index": [float(lf.origin_st[0]), float(lf.origin_st[1])],
        "grid_position_rule": "raw pixel of data[t, s] = microimage_lattice.origin_px + (s0 + s) A + (t0 + t) R",
        "slopes": [float(s) for s in slopes],
        "slope_unit": "lenses along s per angular step (0 = plane imaged onto the array)",
        "slope_distances": [lf.slope_to_distance(s) if lf.slope_to_distance(s) is None or
                            math.isfinite(lf.slope_to_distance(s)) else None for s in slopes],
        "near_far_slope_index": [near, far],
        "views": names,
        "epi_lens_row": epi_row,
    }
    with open(os.path.join(outdir, "lightfield.json"), "w") as f:
        json.dump(description, f, indent=1)
    return sheet_path


def main(argv=None):
    import argparse
    parser = argparse.ArgumentParser(
        prog="plenoptic-decode",
        description="Decode a raw plenoptic render into a 4-D light field L[t, s, v, u] and write "
                    "sub-aperture views, a refocus sweep, an epipolar-plane image and a contact sheet.")
    parser.add_argument("raw", help="the raw lenslet image the render wrote (PNG, EXR, ...)")
    parser.add_argument("metadata", nargs="?",
                        help="its metadata JSON (default: <raw stem>.plenoptic.json beside the image)")
    parser.add_argument("-o", "--output", "--out", dest="output", default=None,
                        help="output folder (default: <raw stem>.lightfield beside the image)")
    parser.add_argument("--contact-sheet", default=None, metavar="PNG",
                        help="also write the contact sheet to this file")
    parser.add_argument("--angular", type=int, default=None,
                        help="angular samples per axis (odd; default: as many 1-px steps as fit the microimage)")
    parser.add_argument("--step", type=float, default=1.0, help="angular sample spacing in pixels (default 1)")
    parser.add_argument("--slopes", default=None,
                        help="refocus sweep LO:HI:COUNT in lenses per angular step (default: the "
                             "depths of the render's depth map if it wrote one, else the outermost "
                             "views shift by -2..+2 lenses; 9 steps)")
    parser.add_argument("--encoding", default="auto",
                        help="raw image encoding: auto (sRGB for 8/16-bit, linear for float), srgb, linear, "
                             "or a gamma number")
    parser.add_argument("--no-gif", action="store_true", help="do not write refocus.gif")
    parser.add_argument("--no-npy", action="store_true", help="do not write lightfield.npy")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress messages")
    args = parser.parse_args(argv)

    def fail(message):
        print("plenoptic-decode: error: %s" % message, file=sys.stderr)
        return 2

    if not (args.step > 0 and math.isfinite(args.step)):
        return fail("--step must be a positive number of pixels")
    if args.encoding not in ("auto", "srgb", "linear"):
        try:
            if not float(args.encoding) > 0:
                raise ValueError
        except ValueError:
            return fail("--encoding must be auto, srgb, linear or a positive gamma")
    try:
        slopes = parse_slopes(args.slopes) if args.slopes else None
    except ValueError as e:
        return fail(str(e))
    meta_path = args.metadata or metadata_path_for(args.raw)
    outdir = args.output or os.path.splitext(args.raw)[0] + ".lightfield"
    progress = Progress(not args.quiet)
    try:
        if not os.path.exists(args.raw):
            return fail("%s: the raw image does not exist" % args.raw)
        raw = read_raw(args.raw, args.encoding)
        meta = load_metadata(meta_path, (raw.shape[1], raw.shape[0]))
        lf = decode(raw, meta, args.angular, args.step, progress)
        if slopes is None:
            slopes = slopes_from_depth_map(lf)
            if slopes is not None:
                progress.stage("refocus sweep from the render's depth map: slopes %+.3f..%+.3f"
                               % (slopes[0], slopes[-1]))
            else:
                slopes = default_slopes(lf)
            reach = max(abs(slopes[0]), abs(slopes[-1])) * np.abs(lf.du[np.any(lf.mask, axis=0)]).max() / lf.step
            if reach < 0.25:
                progress.stage("note: the sweep moves the outermost views by at most %.2f lens; this scene's "
                               "depths hardly refocus (deep depth of field)" % reach)
        title = "%s: %s %s plenoptic render, %d x %d px" % (
            os.path.basename(args.raw), meta.grid, meta.raw.get("microlens_array", {}).get("lens", ""),
            meta.width, meta.height)
        sheet = write_outputs(raw, lf, outdir, slopes, gif=not args.no_gif, npy=not args.no_npy,
                              progress=progress, title=title)
        if args.contact_sheet:
            import shutil
            shutil.copyfile(sheet, args.contact_sheet)
            sheet = args.contact_sheet
    except MetadataError as e:
        return fail("%s: %s" % (meta_path, e))
    except DecodeError as e:
        return fail(str(e))
    except OSError as e:
        return fail("cannot write to %s: %s" % (outdir, e.strerror or e))
    if not args.quiet:
        print("plenoptic-decode: wrote %s" % sheet, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
