# SPDX-License-Identifier: AGPL-3.0-or-later
"""Image reading and writing: raw renders and depth maps in (through OpenImageIO, which the
decoder requires), 8-bit sRGB PNGs out (through Pillow); colour encodings and bilinear sampling.
Pixel (column i, row j) has its centre at (i, j)."""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np
import numpy.typing as npt

from .errors import DecodeError, DependencyError

# How an image's values encode light: 'srgb', 'linear', 'auto' or a gamma.
Encoding = str | float

MISSING_OPENIMAGEIO = ("OpenImageIO's Python module is not installed; the decoder reads every raw image "
                       "(8/16-bit PNG, EXR, ...) through it: on Debian 'apt install python3-openimageio', "
                       "with pip 'pip install OpenImageIO'")

# Formats whose files record no encoding (OpenImageIO reports a fixed guess for JPEG and PNM and
# nothing for BMP): their 8-bit values are taken as sRGB, POV-Ray's default File_Gamma.
_NO_ENCODING_RECORD = {"jpeg": "JPEG", "pnm": "PPM/PNM", "bmp": "BMP"}
_FORMAT_NAMES = dict(_NO_ENCODING_RECORD, png="PNG", openexr="EXR", hdr="Radiance HDR", targa="TGA", tiff="TIFF")


def require_openimageio() -> Any:
    """The OpenImageIO module; DependencyError naming the Debian and pip packages without it."""
    try:
        import OpenImageIO as oiio  # noqa: N813 (Debian's python3-openimageio, pip's OpenImageIO)
    except ImportError as e:
        raise DependencyError(MISSING_OPENIMAGEIO) from e
    return oiio


def srgb_to_linear(x: npt.ArrayLike) -> np.ndarray:
    x = np.asarray(x, dtype=np.float32)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(x: npt.ArrayLike) -> np.ndarray:
    x = np.clip(np.asarray(x, dtype=np.float32), 0.0, 1.0)
    return np.where(x <= 0.0031308, x * 12.92, 1.055 * np.power(x, 1 / 2.4) - 0.055).astype(np.float32)


def check_encoding(encoding: Encoding) -> Encoding:
    """'srgb', 'linear', 'auto' or a positive gamma (number or its text) -> the normalised value
    ('srgb', 'linear', 'auto' or a float); ValueError otherwise."""
    if isinstance(encoding, str) and encoding.lower() in ("auto", "srgb", "linear"):
        return encoding.lower()
    try:
        gamma = float(encoding)
    except (TypeError, ValueError):
        gamma = float("nan")
    if not (gamma > 0 and math.isfinite(gamma)):
        raise ValueError("the encoding must be auto, srgb, linear or a positive gamma, not %r" % (encoding,))
    return "linear" if gamma == 1.0 else gamma


class RawInfo:
    """What the raw image's header says: width, height, channels, file_format (OpenImageIO's name),
    sample ('8-bit integer', '16-bit integer', '16-bit float', ...), is_float, and the encoding
    the decoder applies: 'srgb', 'linear' or a gamma (float; linear = value ** gamma), with
    encoding_source, a phrase saying where it comes from."""

    def __init__(self, path: str, spec: Any, file_format: str, encoding: Encoding = "auto") -> None:
        oiio = require_openimageio()
        self.path = path
        self.width, self.height, self.channels = spec.width, spec.height, spec.nchannels
        self.file_format = file_format
        basetype = spec.format.basetype
        self.is_float = basetype in (oiio.FLOAT, oiio.HALF, oiio.DOUBLE)
        self.sample = "%d-bit %s" % (8 * spec.format.size(), "float" if self.is_float else "integer")
        self.colour_space = spec.get_string_attribute("oiio:ColorSpace", "")
        self.file_gamma = spec.get_float_attribute("oiio:Gamma", 0.0)
        encoding = check_encoding(encoding)
        if encoding != "auto":
            self.encoding, self.encoding_source = encoding, "--encoding"
        else:
            self.encoding, self.encoding_source = self._file_encoding()

    def _file_encoding(self):
        """The encoding the file itself records, as OpenImageIO reports it."""
        if self.is_float:
            return "linear", "floating-point pixels are linear"
        if self.file_format in _NO_ENCODING_RECORD:
            return "srgb", ("assumed: a %s file records no encoding; sRGB is POV-Ray's default File_Gamma "
                            "(--encoding linear for a File_Gamma=1.0 render)" % _NO_ENCODING_RECORD[self.file_format])
        told = "the file's own, as OpenImageIO reports it: oiio:ColorSpace %r%s" % (
            self.colour_space, ", oiio:Gamma %g" % self.file_gamma if self.file_gamma > 0 else "")
        name = self.colour_space.lower()
        # OpenImageIO's names: 2.4 'linear', 'sRGB', 'Gamma2.2'; older 'Linear', 'GammaCorrected';
        # 3.x 'lin_srgb', 'lin_rec709_scene', 'srgb_rec709_scene', 'g22_rec709', 'Gamma1.8'.
        if name in ("linear", "scene_linear") or name.startswith("lin_") or name.startswith("linear"):
            return "linear", told
        if "srgb" in name:
            return "srgb", told
        gamma = self.file_gamma
        if not gamma > 0:
            match = re.match(r"^gamma\s*([0-9]*\.?[0-9]+)$", name) or re.match(r"^g([0-9])([0-9])_", name)
            if match:
                gamma = float(match.group(1) if match.lastindex == 1 else match.group(1) + "." + match.group(2))
        if gamma > 0:
            return ("linear" if abs(gamma - 1.0) < 1e-3 else float(gamma)), told
        return "srgb", ("assumed: the file records no encoding OpenImageIO names (oiio:ColorSpace %r); sRGB is "
                        "POV-Ray's default File_Gamma" % self.colour_space)

    def describe(self, encoding: bool = True) -> str:
        """'96 x 72 PNG, 16-bit integer, encoding linear (the file's own, ...)'; without the
        encoding (for a file read as DN, whose colour encoding does not apply) when encoding is False."""
        layout = "%d x %d %s, %s" % (self.width, self.height, _FORMAT_NAMES.get(self.file_format, self.file_format),
                                     self.sample)
        if not encoding:
            return layout
        told = self.encoding if isinstance(self.encoding, str) else "gamma %g" % self.encoding
        return "%s, encoding %s (%s)" % (layout, told, self.encoding_source)


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# PNG colour type -> (channels, colour name, has alpha); sBIT holds one byte per channel.
_PNG_COLOUR_TYPES = {0: (1, "grey", False), 2: (3, "RGB", False), 3: (3, "palette", False),
                     4: (2, "grey + alpha", True), 6: (4, "RGBA", True)}
# Chunks that record how a PNG's values encode light: what a picture carries and a raw does not.
PNG_ENCODING_CHUNKS = ("gAMA", "sRGB", "iCCP", "cICP")


class PngLayout:
    """What a PNG's header chunks say (the chunks before the first IDAT): bit_depth (per sample),
    channels, colour ('grey', 'RGB', ...), alpha, sbit (the sBIT chunk's significant bits per
    channel, a tuple, or None without one) and encoding_chunks (those of PNG_ENCODING_CHUNKS it has).
    OpenImageIO does not report sBIT, so the chunks are read here: a file format fact."""

    def __init__(self, bit_depth, colour_type, sbit, chunks):
        self.bit_depth = bit_depth
        self.channels, self.colour, self.alpha = _PNG_COLOUR_TYPES[colour_type]
        self.sbit = sbit
        self.encoding_chunks = tuple(name for name in PNG_ENCODING_CHUNKS if name in chunks)

    def describe(self):
        """'a 16-bit grey PNG, sBIT 12, no colour-encoding chunk'."""
        bits = sorted(set(self.sbit or ()))
        sbit = ("sBIT %s" % "/".join(str(b) for b in (bits if len(bits) == 1 else self.sbit))) if bits \
            else "no sBIT chunk"
        encoding = ("colour encoding in %s" % ", ".join(self.encoding_chunks) if self.encoding_chunks
                    else "no colour-encoding chunk")
        return "a%s %d-bit %s PNG, %s, %s" % ("n" if self.bit_depth == 8 else "", self.bit_depth, self.colour,
                                             sbit, encoding)


def png_layout(path: str) -> PngLayout | None:
    """The PngLayout of a PNG file, or None when the file is not a PNG. DecodeError when it
    starts as a PNG but its header chunks are broken."""
    import struct
    try:
        with open(path, "rb") as f:
            if f.read(8) != _PNG_SIGNATURE:
                return None
            header, sbit, chunks = None, None, set()
            while True:
                head = f.read(8)
                if len(head) < 8:
                    raise DecodeError("%s: a PNG whose chunks end before its image data" % path)
                length, kind = struct.unpack(">I4s", head)
                kind = kind.decode("latin-1")
                if kind in ("IDAT", "IEND"):
                    break
                if length > 1 << 24:
                    data = b""
                    f.seek(length + 4, 1)
                else:
                    data = f.read(length)
                    if len(data) < length or len(f.read(4)) < 4:
                        raise DecodeError("%s: a PNG cut short in its %s chunk" % (path, kind))
                chunks.add(kind)
                if kind == "IHDR" and len(data) >= 10:
                    header = (data[8], data[9])
                elif kind == "sBIT":
                    sbit = tuple(data)
    except OSError as e:
        raise DecodeError("cannot read %s: %s" % (path, e.strerror or e))
    if header is None or header[1] not in _PNG_COLOUR_TYPES:
        raise DecodeError("%s: a PNG without a valid IHDR chunk" % path)
    bit_depth, colour_type = header
    layout = PngLayout(bit_depth, colour_type, None, chunks)
    if sbit is not None:
        wanted = 3 if colour_type == 3 else layout.channels
        layout.sbit = sbit[:wanted] if len(sbit) >= wanted else sbit
    return layout


class ImageReadError(OSError):
    """An image OpenImageIO cannot open or read: path and reason (OpenImageIO's words, on one line)."""

    def __init__(self, path: str, reason: str) -> None:
        super().__init__("cannot read %s: %s" % (path, reason))
        self.path = path
        self.reason = reason


def _one_line(text: str, default: str) -> str:
    """OpenImageIO's error text (sometimes several lines) as one line."""
    return "; ".join(line.strip() for line in (text or "").splitlines() if line.strip()) or default


class ImageFile:
    """An image file opened with OpenImageIO's ImageInput, its header read (spec, file_format:
    OpenImageIO's format name such as 'png' or 'openexr'), its pixels not yet. The one way this
    package (and the tests' helper) reads images: ImageInput reads the file itself each time,
    where an ImageBuf reads through OpenImageIO's shared image cache, which hands back the pixels
    first read from a path after the file was written again (the same name rendered twice in a
    second). Use as a context manager, or call close()."""

    def __init__(self, path: str, unassociated_alpha: bool = False) -> None:
        oiio = require_openimageio()
        self.path = path
        config = None
        if unassociated_alpha:  # alpha as stored: no premultiplying on reading (PNG's is unassociated)
            config = oiio.ImageSpec()
            config.attribute("oiio:UnassociatedAlpha", 1)
        self._input = oiio.ImageInput.open(path, config) if config is not None else oiio.ImageInput.open(path)
        if self._input is None:
            raise ImageReadError(path, _one_line(oiio.geterror(), "unknown format"))
        self.spec = self._input.spec()
        self.file_format: str = self._input.format_name()
        if self.spec.width <= 0 or self.spec.height <= 0:
            self.close()
            raise ImageReadError(path, "unknown format")

    @property
    def width(self) -> int:
        return int(self.spec.width)

    @property
    def height(self) -> int:
        return int(self.spec.height)

    @property
    def channels(self) -> int:
        return int(self.spec.nchannels)

    def read(self, native: bool = False) -> np.ndarray:
        """The pixels as an (H, W, C) array: float32 (integers scaled to 0..1, as OpenImageIO
        gives them) or, with native, in the file's own sample type."""
        oiio = require_openimageio()
        pixels = self._input.read_image(self.spec.format if native else oiio.FLOAT)
        if pixels is None or not isinstance(pixels, np.ndarray) or pixels.size == 0:
            raise ImageReadError(self.path, _one_line(self._input.geterror(), "no pixels"))
        return np.asarray(pixels).reshape(self.height, self.width, self.channels)

    def close(self) -> None:
        if self._input is not None:
            self._input.close()
            self._input = None

    def __enter__(self) -> ImageFile:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def read_image(path: str, native: bool = False, unassociated_alpha: bool = False) -> np.ndarray:
    """The pixels of any image OpenImageIO reads, (H, W, C), as ImageFile.read gives them.
    Raises ImageReadError, or DependencyError without OpenImageIO."""
    with ImageFile(path, unassociated_alpha) as image:
        return image.read(native)


def _open_raw(path: str) -> ImageFile:
    """The raw image's ImageFile (header read, no pixels yet); DecodeError naming the file."""
    try:
        return ImageFile(path)
    except ImageReadError as e:
        raise DecodeError("cannot read raw image %s: %s" % (path, e.reason)) from None


def inspect_raw(path: str, encoding: Encoding = "auto") -> RawInfo:
    """The raw image's RawInfo from its header alone (size, sample type, encoding), without
    reading its pixels. Raises DecodeError, or DependencyError without OpenImageIO."""
    with _open_raw(path) as image:
        return RawInfo(path, image.spec, image.file_format, encoding)


def to_linear(pixels: npt.ArrayLike, encoding: Encoding) -> np.ndarray:
    """Encoded values -> linear light, for encoding 'srgb', 'linear' or a gamma (float)."""
    if encoding == "srgb":
        return srgb_to_linear(pixels)
    if encoding == "linear":
        return np.asarray(pixels, dtype=np.float32)
    return np.power(np.clip(pixels, 0, None), float(encoding)).astype(np.float32)


def read_raw_image(path: str, encoding: Encoding = "auto") -> tuple[np.ndarray, RawInfo]:
    """The raw image as float32 (H, W, 3) linear light, and its RawInfo.

    encoding: 'auto' (the file's own encoding: a PNG's sRGB or gAMA chunk as OpenImageIO reports
    it, linear for float files such as EXR, sRGB for formats that record none), or an override:
    'srgb', 'linear', or a number (a pure power-law gamma: linear = value ** gamma).
    Raises DecodeError, or DependencyError without OpenImageIO."""
    with _open_raw(path) as image:
        info = RawInfo(path, image.spec, image.file_format, encoding)
        try:
            pixels = image.read()
        except ImageReadError as e:
            raise DecodeError("cannot read raw image %s: %s" % (path, e.reason)) from None
    if pixels.shape[2] == 1:
        pixels = np.repeat(pixels, 3, axis=2)
    elif pixels.shape[2] == 2:  # grey + alpha
        pixels = np.repeat(pixels[:, :, :1], 3, axis=2)
    pixels = to_linear(pixels[:, :, :3], info.encoding)
    return np.ascontiguousarray(pixels, dtype=np.float32), info


def read_raw(path: str, encoding: Encoding = "auto") -> np.ndarray:
    """The raw image as float32 (H, W, 3), linear light (see read_raw_image for `encoding`)."""
    return read_raw_image(path, encoding)[0]


def read_stored(path: str) -> np.ndarray:
    """The image's values as stored (OpenImageIO's 0..1 for integers), (H, W, C) float32, no
    decoding; DecodeError naming the file when it cannot be read."""
    try:
        return np.asarray(read_image(path), dtype=np.float32)
    except ImageReadError as e:
        raise DecodeError(str(e)) from None


def read_depth_map(path: str) -> np.ndarray | None:
    """The first channel of a depth map (EXR) as a float array, or None when it cannot be read
    (or OpenImageIO is missing)."""
    try:
        return read_image(path)[..., 0]
    except (ImportError, OSError):
        return None


def to_8bit(image: npt.ArrayLike) -> np.ndarray:
    """Linear float image -> 8-bit sRGB array."""
    return (linear_to_srgb(image) * 255.0 + 0.5).astype(np.uint8)


def save_png(path: str, image: npt.ArrayLike) -> None:
    from PIL import Image
    srgb = to_8bit(image)
    if srgb.ndim == 3 and srgb.shape[2] == 1:
        srgb = srgb[:, :, 0]
    Image.fromarray(srgb).save(path)


def save_exr(path: str, image: npt.ArrayLike) -> None:
    """A linear float image (H, W, C) as a float OpenEXR file (OpenImageIO)."""
    oiio = require_openimageio()
    image = np.ascontiguousarray(image, dtype=np.float32)
    spec = oiio.ImageSpec(image.shape[1], image.shape[0], image.shape[2], oiio.FLOAT)
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec):
        raise OSError("cannot write %s: %s" % (path, oiio.geterror() or "no EXR writer"))
    ok = out.write_image(image)
    out.close()
    if not ok:
        raise OSError("cannot write %s: %s" % (path, out.geterror()))


def scaled_pil_image(image: npt.ArrayLike, width: int | None = None, height: int | None = None,
                     aspect: float = 1.0) -> Any:
    """Linear image -> PIL image scaled (nearest neighbour: every lens stays a visible cell) to
    fit width x height, with rows stretched by `aspect` (cell height / width)."""
    from PIL import Image
    im = Image.fromarray(to_8bit(image))
    w, h = im.size
    stretched_h = h * aspect
    scale = min(width / w if width else 1e9, height / stretched_h if height else 1e9)
    size = (max(1, int(round(w * scale))), max(1, int(round(stretched_h * scale))))
    return im.resize(size, Image.NEAREST)


def bilinear(image: np.ndarray, x: npt.ArrayLike, y: npt.ArrayLike) -> np.ndarray:
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
