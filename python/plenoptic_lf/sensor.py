# SPDX-License-Identifier: AGPL-3.0-or-later
"""From the sensor's raw back to the picture: DN to linear values, demosaicing, devignetting
(docs/sensor.md, "Decoding raws").

The render's read-out (docs/sensor.md, "The chain") writes DN = K + round(e g), with e the
electrons, g = (2^B - 1 - K) / E the gain and X electrons for a picture value of 1. So a site's
picture value is (DN - K) / (g X), noise and all. A Bayer mosaic holds one colour per site;
demosaic_bilinear fills in the other two from the nearest sites of their colour (bilinear
interpolation, exact where the picture is locally affine). Devignetting divides by the camera's
white image, where it is bright enough to carry light.

Which input is which (picture_reading, white_reading) follows the options, the file's name in the
metadata and its content: the raw and a white image in DN are 16-bit PNGs with an sBIT chunk equal
to the read-out's bit depth, one channel for a mosaic, and no colour-encoding chunk; a linear
white image has sBIT 16; the render's PNG picture always carries gAMA.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from .errors import DecodeError

# Sites of each colour in a 2 x 2 cell (row, column): top-left, top-right, bottom-left, bottom-right.
_CELLS = {"rggb": "RGGB", "bggr": "BGGR", "grbg": "GRBG", "gbrg": "GBRG"}


def white_image_of(meta, white_path):
    """The metadata's white_images entry of this file (its values: "linear" or "dn"), or None."""
    return meta.white_image(white_path)


WHITE_VALUES = ("dn", "linear")


class Reading:
    """How to read one input: kind 'dn' (the sensor's read-out in DN, through dn_to_linear and,
    for a mosaic, demosaic_bilinear), 'linear' (a linear white image: stored value x scale) or
    'picture' (the render's image, in its encoding); why, a phrase for the progress line."""

    def __init__(self, kind, why, scale=1.0, read_out=None, warning=None):
        self.kind, self.why, self.scale, self.read_out = kind, why, scale, read_out
        self.warning = warning  # a sentence for stderr, or None


def read_out_bit_depth(read_out):
    """The read-out's bit depth B (1..16); DecodeError when the metadata garbles it."""
    bits = read_out.get("bit_depth")
    if isinstance(bits, bool) or not isinstance(bits, int) or not 1 <= bits <= 16:
        raise DecodeError("the metadata's sensor.read_out.bit_depth must be a whole number from 1 to 16, found %r"
                          % (bits,))
    return bits


def _dn_channels(read_out):
    return 1 if read_out.get("bayer") else 3


def _expected_dn(read_out):
    """What a file of this read-out's DN is, as the renderer writes it (raw and white images alike)."""
    colour = ("grey (one channel: the %s Bayer mosaic)" % read_out["bayer"] if read_out.get("bayer")
              else "RGB (no Bayer mosaic)")
    return ("a 16-bit %s PNG, sBIT %d (the read-out's bit_depth), no colour-encoding chunk"
            % (colour, read_out_bit_depth(read_out)))


EXPECTED_LINEAR = "a 16-bit grey or RGB PNG, sBIT 16, no colour-encoding chunk"


def _fits_dn(layout, read_out, need_sbit):
    """Whether a PNG's layout can hold this read-out's DN: 16-bit, the read-out's channels (one for
    a mosaic, three otherwise), no alpha, no colour encoding (a picture's gAMA / sRGB / iCCP), and
    sBIT = B on every channel (or, unless need_sbit, no sBIT chunk at all: a re-saved file)."""
    if layout is None or read_out is None:
        return False
    if layout.bit_depth != 16 or layout.alpha or layout.colour == "palette" or layout.encoding_chunks:
        return False
    if layout.channels != _dn_channels(read_out):
        return False
    if layout.sbit is None:
        return not need_sbit
    return all(b == read_out_bit_depth(read_out) for b in layout.sbit)


def _fits_linear(layout, need_sbit):
    """Whether a PNG's layout is that of a linear white image: 16-bit grey or RGB, no alpha, no
    colour encoding, sBIT 16 (or, unless need_sbit, none)."""
    if layout is None or layout.bit_depth != 16 or layout.alpha or layout.colour == "palette":
        return False
    if layout.encoding_chunks:
        return False
    if layout.sbit is None:
        return not need_sbit
    return all(b == 16 for b in layout.sbit)


def _found(layout):
    return layout.describe() if layout is not None else "not a PNG file"


def _metadata_read_out(meta):
    return meta.read_out


def picture_reading(meta, path, layout, raw=False, encoding_given=False):
    """How to read the decoder's input (docs/sensor.md, "Decoding raws"), in this order:
    --raw, or the name of the metadata's raw (sensor.read_out.raw_file): the raw in DN, refused
    unless its content can be (16-bit, the read-out's channels, sBIT = bit_depth or no sBIT, no
    colour encoding); the name of a white_images entry: that white image; otherwise content with
    the raw's full signature (sBIT included) is the raw in DN, anything else a picture.
    `layout` is the file's PngLayout (None: not a PNG). Contradictions raise DecodeError."""
    import os
    name = os.path.basename(path)
    read_out = _metadata_read_out(meta)
    entry = white_image_of(meta, path)
    if raw:
        if read_out is None:
            raise DecodeError("--raw: the metadata records no read-out (its sensor.read_out is null), so there is "
                              "no raw in DN to decode; give the rendered picture without --raw")
        if entry is not None and entry.values == "linear":
            raise DecodeError("--raw: %s is the metadata's linear white image (white_images), not a raw in DN" % name)
        if not _fits_dn(layout, read_out, need_sbit=False):
            raise DecodeError("--raw: %s is not the sensor's raw in DN: expected %s; found %s"
                              % (path, _expected_dn(read_out), _found(layout)))
        reading = Reading("dn", "the sensor's raw in DN (--raw)", read_out=read_out)
    elif read_out is not None and read_out.get("raw_file") == name:
        if not _fits_dn(layout, read_out, need_sbit=False):
            raise DecodeError("%s has the name of the sensor's raw (the metadata's sensor.read_out.raw_file) but not "
                              "its content: expected %s; found %s" % (path, _expected_dn(read_out), _found(layout)))
        reading = Reading("dn", "the sensor's raw in DN (the metadata's raw_file)", read_out=read_out)
    elif entry is not None:
        reading = white_reading(meta, path, layout)
    elif _fits_dn(layout, read_out, need_sbit=True):
        reading = Reading("dn", "the sensor's raw in DN, recognised by its content (16-bit, sBIT %d = the "
                          "read-out's bit_depth, no colour encoding)" % read_out_bit_depth(read_out), read_out=read_out)
    elif _fits_dn(layout, read_out, need_sbit=False):
        # The raw's layout without its sBIT chunk, as a tool that re-saves a 16-bit PNG leaves it.
        return Reading("picture", "the rendered picture", warning=(
            "%s is a 16-bit %s PNG without an sBIT or colour-encoding chunk, as the sensor's raw is once another tool "
            "re-saves it; it is read as a picture (such a PNG is sRGB by the PNG rules): give --raw if it is the raw "
            "in DN" % (path, layout.colour)))
    else:
        return Reading("picture", "the rendered picture")
    if encoding_given:
        raise DecodeError("--encoding applies to a rendered picture, and %s is read as %s: give it without --encoding"
                          % (name, reading.why))
    return reading


def white_reading(meta, path, layout, values=None, scale=None):
    """How to read a white image (--white; docs/sensor.md, "Decoding raws"): its white_images
    entry in the metadata when the name is one (values and scale from there; --white-values and
    --white-scale must agree); else --white-values dn|linear (--white-scale alone means linear,
    and a linear one needs it); else its content: the read-out's DN signature or a linear white
    image's (16-bit, sBIT 16), refused when it fits both (a 16-bit read-out) or neither.
    DecodeError for every refusal."""
    import os
    name = os.path.basename(path)
    read_out = _metadata_read_out(meta)
    entry = white_image_of(meta, path)
    if values is not None and values not in WHITE_VALUES:
        raise DecodeError("--white-values must be dn or linear, found %r" % (values,))
    if entry is not None:
        told = entry.values
        if told not in WHITE_VALUES:
            raise DecodeError("the metadata's white_images entry of %s has values %r: dn or linear expected"
                              % (name, told))
        if values is not None and values != told:
            raise DecodeError("--white-values %s contradicts the metadata, whose white_images entry says %s is %s"
                              % (values, name, told))
        told_scale = entry.scale
        if told == "linear" and not (told_scale > 0 and told_scale < float("inf")):
            raise DecodeError("the metadata's white_images entry of %s has scale %r: a positive number expected"
                              % (name, entry.raw_scale))
        if scale is not None and (told == "dn" or scale != told_scale):
            raise DecodeError("--white-scale %g contradicts the metadata, whose white_images entry of %s says %s"
                              % (scale, name, "values dn (no scale)" if told == "dn" else "scale %g" % told_scale))
        values, source = told, "the metadata's white_images entry"
        scale = told_scale if told == "linear" else None
        need_sbit = False
    elif values is not None or scale is not None:
        if values is None:
            values, source = "linear", "--white-scale (a linear white image)"
        else:
            source = "--white-values %s" % values
        need_sbit = False
    else:
        dn = _fits_dn(layout, read_out, need_sbit=True)
        linear = _fits_linear(layout, need_sbit=True)
        if dn and linear:
            raise DecodeError("%s: the white image's content fits both a white image in DN (the read-out's bit_depth "
                              "is 16) and a linear one, and its name is not in the metadata's white_images: say which "
                              "with --white-values dn, or --white-values linear with --white-scale S" % path)
        if not (dn or linear):
            expected = (("%s (in DN), or %s (linear)" % (_expected_dn(read_out), EXPECTED_LINEAR)) if read_out
                        else "%s (linear; the metadata records no read-out, so no white image in DN)" % EXPECTED_LINEAR)
            resaved = (layout is not None and layout.bit_depth == 16 and layout.sbit is None
                       and not layout.encoding_chunks)
            raise DecodeError("%s is not a white image the renderer writes: expected %s; found %s%s"
                              % (path, expected, _found(layout),
                                 " (--white-values dn or linear says what a white image re-saved without its sBIT "
                                 "chunk holds)" if resaved else ""))
        values = "dn" if dn else "linear"
        source = "recognised by its content: %s" % ("16-bit, sBIT %d = the read-out's bit_depth"
                                                     % read_out_bit_depth(read_out) if dn else "16-bit, sBIT 16")
        need_sbit = True
    if values == "dn":
        if read_out is None:
            raise DecodeError("%s: a white image in DN needs the read-out, and the metadata records none (its "
                              "sensor.read_out is null)" % name)
        if scale is not None:
            raise DecodeError("--white-scale applies to a linear white image, and %s is in DN (%s)" % (name, source))
        if not _fits_dn(layout, read_out, need_sbit):
            raise DecodeError("%s is not a white image in DN (%s): expected %s; found %s"
                              % (path, source, _expected_dn(read_out), _found(layout)))
        return Reading("dn", "a white image in DN, %s" % source, read_out=read_out)
    if not _fits_linear(layout, need_sbit):
        raise DecodeError("%s is not a linear white image (%s): expected %s; found %s"
                          % (path, source, EXPECTED_LINEAR, _found(layout)))
    if scale is None:
        known = sorted({"%g" % e.scale for e in meta.white_images if e.values == "linear"})
        raise DecodeError("%s is a linear white image (%s) whose name is not in the metadata's white_images, so its "
                          "scale (stored value x scale = irradiance) is unknown: give --white-scale S%s"
                          % (path, source, " (the metadata's linear white images have scale %s)" % ", ".join(known)
                                           if known else ""))
    if not (scale > 0 and scale < float("inf")):
        raise DecodeError("--white-scale must be a positive number, found %r" % (scale,))
    return Reading("linear", "a linear white image, scale %g, %s" % (scale, source), scale=scale)


def _same_file(a, b):
    """Whether two paths name one file: the same real path, or (hard links) the same inode."""
    import os
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def check_white_is_not_the_raw(meta, raw_path, white_path):
    """DecodeError when --white names the decoder's own input or the file the metadata names as the
    sensor's raw (sensor.read_out.raw_file, beside the metadata): a raw has a white image's layout,
    and dividing a picture by its own raw gives a light field of about 1, not the scene."""
    import os
    if _same_file(white_path, raw_path):
        raise DecodeError("--white %s is the input itself: give the camera's white image (the render's "
                          "<stem>.white.png), not the image being decoded" % white_path)
    read_out = _metadata_read_out(meta)
    name = read_out.get("raw_file") if read_out else None
    if isinstance(name, str) and name:
        raw_file = os.path.join(os.path.dirname(os.path.abspath(meta.path)), name)
        if os.path.exists(raw_file) and _same_file(white_path, raw_file):
            raise DecodeError("--white %s is the sensor's raw (the file the metadata names in sensor.read_out.raw_file), "
                              "not a white image: give the camera's white image (the render's <stem>.white.png)"
                              % white_path)


def check_dn_range(path, dn, read_out):
    """DecodeError when a value read as DN exceeds the read-out's largest, 2^B - 1."""
    largest = (1 << read_out_bit_depth(read_out)) - 1
    top = float(np.max(dn)) if np.size(dn) else 0.0
    if top > largest:
        raise DecodeError("%s holds values up to %d, above %d = 2^%d - 1, the largest DN of the read-out's bit_depth: "
                          "not this sensor's DN" % (path, top, largest, read_out_bit_depth(read_out)))


def dn_to_linear(pixels, read_out, path=None):
    """Pixels read from a 16-bit raw PNG (OpenImageIO's 0..1: DN / 65535) -> picture values; with
    `path`, DecodeError naming it when a value exceeds the bit depth's largest DN."""
    try:
        black = float(read_out["black_level_dn"])
        gain = float(read_out["gain_dn_per_e"])
        exposure = float(read_out["exposure_e"])
    except (KeyError, TypeError, ValueError):
        raise DecodeError("the metadata's sensor.read_out lacks black_level_dn, gain_dn_per_e or exposure_e")
    if not (gain > 0 and exposure > 0):
        raise DecodeError("the metadata's sensor.read_out has a gain or exposure that is not positive")
    dn = np.rint(np.asarray(pixels, dtype=np.float64) * 65535.0)
    if path is not None:
        check_dn_range(path, dn, read_out)
    return ((dn - black) / (gain * exposure)).astype(np.float32)


def demosaic_bilinear(mosaic: npt.ArrayLike, pattern: str) -> np.ndarray:
    """(H, W) single-colour sites of a Bayer `pattern` ('rggb', 'bggr', 'grbg', 'gbrg') -> (H, W, 3).

    Each colour: its sites kept, the others the mean of the nearest sites of that colour (the two
    or four neighbours), by normalised convolution, so borders use the sites that exist."""
    from scipy import ndimage
    cell = _CELLS.get(pattern)
    if cell is None:
        raise DecodeError("unknown Bayer pattern %r (rggb, bggr, grbg, gbrg)" % (pattern,))
    mosaic = np.asarray(mosaic, dtype=np.float64)
    H, W = mosaic.shape
    rows, cols = np.mgrid[0:H, 0:W]
    kernel = np.array([[0.25, 0.5, 0.25], [0.5, 1.0, 0.5], [0.25, 0.5, 0.25]])
    out = np.empty((H, W, 3), np.float32)
    for c, colour in enumerate("RGB"):
        sites = np.zeros((H, W), bool)
        for index, name in enumerate(cell):
            if name == colour:
                sites |= (rows % 2 == index // 2) & (cols % 2 == index % 2)
        values = ndimage.convolve(np.where(sites, mosaic, 0.0), kernel, mode="constant")
        weights = ndimage.convolve(sites.astype(np.float64), kernel, mode="constant")
        # Green has four direct neighbours: the diagonal ones (weight 0.25) are not green, so
        # its non-sites average the four greens around them; red and blue average 2 or 4.
        out[..., c] = np.where(sites, mosaic, values / np.maximum(weights, 1e-12))
    return out


def devignette(picture: npt.ArrayLike, white: npt.ArrayLike, threshold: float = 0.1) -> np.ndarray:
    """picture / white where the white image exceeds `threshold` times its 99.9th percentile (the
    light's reach), 0 elsewhere: what every lens passes becomes what the scene sent."""
    picture = np.asarray(picture, dtype=np.float32)
    white = np.asarray(white, dtype=np.float32)
    if white.shape[:2] != picture.shape[:2]:
        raise DecodeError("the white image is %d x %d but the raw is %d x %d"
                          % (white.shape[1], white.shape[0], picture.shape[1], picture.shape[0]))
    if white.ndim == 2:
        white = white[..., None]
    level = float(np.percentile(white, 99.9))
    if not level > 0:
        raise DecodeError("the white image is black: nothing to devignette with")
    lit = white > threshold * level
    return np.where(lit, picture / np.where(lit, white, 1.0), 0.0).astype(np.float32)
