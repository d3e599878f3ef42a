# SPDX-License-Identifier: AGPL-3.0-or-later
"""Image reading and writing: raw renders and depth maps in (through OpenImageIO, with Pillow
as a fallback for 8-bit raws), 8-bit sRGB PNGs out (through Pillow); colour encodings and
bilinear sampling. Pixel (column i, row j) has its centre at (i, j)."""

import numpy as np

from .errors import DecodeError


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
    pixels = None
    is_float = False
    try:
        import OpenImageIO as oiio  # noqa: N813 (Debian's python3-openimageio)
        buf = oiio.ImageBuf(path)
        spec = buf.spec()
        if buf.has_error or spec.width == 0:
            raise DecodeError("cannot read raw image %s: %s" % (path, buf.geterror().strip() or "unknown format"))
        is_float = spec.format.basetype in (oiio.FLOAT, oiio.HALF, oiio.DOUBLE)
        pixels = np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32)
    except ImportError:
        try:
            from PIL import Image
            with Image.open(path) as im:
                mode = im.mode
                stored = np.asarray(im.convert("RGB") if mode not in ("I;16", "I", "F") else im)
            if stored.dtype == np.uint8:
                pixels = stored.astype(np.float32) / 255.0
            elif mode == "F":
                pixels = stored.astype(np.float32)
                is_float = True
            else:
                pixels = stored.astype(np.float32) / 65535.0
        except OSError as e:
            raise DecodeError("cannot read raw image %s: %s" % (path, e))
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    if pixels.shape[2] == 1:
        pixels = np.repeat(pixels, 3, axis=2)
    elif pixels.shape[2] == 2:  # grey + alpha
        pixels = np.repeat(pixels[:, :, :1], 3, axis=2)
    pixels = pixels[:, :, :3]
    if encoding == "auto":
        encoding = "linear" if is_float else "srgb"
    if encoding == "srgb":
        pixels = srgb_to_linear(pixels)
    elif encoding != "linear":
        pixels = np.power(np.clip(pixels, 0, None), float(encoding)).astype(np.float32)
    return np.ascontiguousarray(pixels, dtype=np.float32)


def read_depth_map(path):
    """The first channel of a depth map (EXR) as a float array, or None when it cannot be read
    (or OpenImageIO is missing)."""
    try:
        import OpenImageIO as oiio
        buf = oiio.ImageBuf(path)
        if buf.has_error:
            return None
        return np.asarray(buf.get_pixels(oiio.FLOAT))[..., 0]
    except (ImportError, OSError):
        return None


def to_8bit(image):
    """Linear float image -> 8-bit sRGB array."""
    return (linear_to_srgb(image) * 255.0 + 0.5).astype(np.uint8)


def save_png(path, image):
    from PIL import Image
    srgb = to_8bit(image)
    if srgb.ndim == 3 and srgb.shape[2] == 1:
        srgb = srgb[:, :, 0]
    Image.fromarray(srgb).save(path)


def scaled_pil_image(image, width=None, height=None, aspect=1.0):
    """Linear image -> PIL image scaled (nearest neighbour: every lens stays a visible cell) to
    fit width x height, with rows stretched by `aspect` (cell height / width)."""
    from PIL import Image
    im = Image.fromarray(to_8bit(image))
    w, h = im.size
    stretched_h = h * aspect
    scale = min(width / w if width else 1e9, height / stretched_h if height else 1e9)
    size = (max(1, int(round(w * scale))), max(1, int(round(stretched_h * scale))))
    return im.resize(size, Image.NEAREST)


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
