# SPDX-License-Identifier: AGPL-3.0-or-later
"""From the sensor's raw back to the picture: DN to linear values, demosaicing, devignetting
(issue 14, item 6; docs/sensor.md, "Decoding raws").

The render's read-out (docs/sensor.md, "The chain") writes DN = K + round(e g), with e the
electrons, g = (2^B - 1 - K) / E the gain and X electrons for a picture value of 1. So a site's
picture value is (DN - K) / (g X), noise and all. A Bayer mosaic holds one colour per site;
demosaic_bilinear fills in the other two from the nearest sites of their colour (bilinear
interpolation, exact where the picture is locally affine). Devignetting divides by the camera's
white image, where it is bright enough to carry light.
"""

import numpy as np

from .errors import DecodeError

# Sites of each colour in a 2 x 2 cell (row, column): top-left, top-right, bottom-left, bottom-right.
_CELLS = {"rggb": "RGGB", "bggr": "BGGR", "grbg": "GRBG", "gbrg": "GBRG"}


def read_out_of(meta, raw_path):
    """The metadata's sensor.read_out when `raw_path` is the raw it names, else None."""
    import os
    read_out = meta.raw.get("sensor", {}).get("read_out")
    if not isinstance(read_out, dict) or read_out.get("raw_file") != os.path.basename(raw_path):
        return None
    return read_out


def white_image_of(meta, white_path):
    """The metadata's white_images entry of this file (its "values": "linear" or "dn"), or None."""
    import os
    for entry in meta.raw.get("white_images") or []:
        if isinstance(entry, dict) and entry.get("file") == os.path.basename(white_path):
            return entry
    return None


def dn_to_linear(pixels, read_out):
    """Pixels read from a 16-bit raw PNG (OpenImageIO's 0..1: DN / 65535) -> picture values."""
    try:
        black = float(read_out["black_level_dn"])
        gain = float(read_out["gain_dn_per_e"])
        exposure = float(read_out["exposure_e"])
    except (KeyError, TypeError, ValueError):
        raise DecodeError("the metadata's sensor.read_out lacks black_level_dn, gain_dn_per_e or exposure_e")
    if not (gain > 0 and exposure > 0):
        raise DecodeError("the metadata's sensor.read_out has a gain or exposure that is not positive")
    dn = np.rint(np.asarray(pixels, dtype=np.float64) * 65535.0)
    return ((dn - black) / (gain * exposure)).astype(np.float32)


def demosaic_bilinear(mosaic, pattern):
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


def devignette(picture, white, threshold=0.1):
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
