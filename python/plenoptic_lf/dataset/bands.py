# SPDX-License-Identifier: AGPL-3.0-or-later
"""Row bands: one raw rendered as N bands of rows (+SR/+ER), merged by rows into the image one
render would have written. POV-Ray 3.7 writes a partial render as a full-height image with the
other rows black (and the plenoptic depth maps with -1 there), so band k's rows are taken from
band k's files; the files that do not depend on the rows (metadata, white images, microimage
centres) must be byte-identical across bands and are taken from the first."""

import os

# Files written beside the image that hold one value per pixel, merged by rows.
ROW_SUFFIXES = (".depth.exr", ".virtual_depth.exr", ".raw.png")


class BandError(Exception):
    pass


def band_rows(height, count):
    """[(first, last)] 0-based inclusive rows of `count` bands as even as whole rows allow."""
    edges = [round(k * height / count) for k in range(count + 1)]
    return [(edges[k], edges[k + 1] - 1) for k in range(count) if edges[k + 1] > edges[k]]


def _read(path):
    from ..images import ImageFile, ImageReadError
    # Alpha as stored (a PNG's is unassociated): OpenImageIO would otherwise premultiply it on
    # reading and divide on writing, which is lossy. Values in the file's own sample type.
    try:
        with ImageFile(path, unassociated_alpha=True) as image:
            return image.spec, image.read(native=True)
    except ImageReadError as e:
        raise BandError(str(e)) from None


def _write(path, spec, pixels):
    import numpy as np
    import OpenImageIO as oiio
    spec.attribute("oiio:UnassociatedAlpha", 1)
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec):
        raise BandError("cannot write %s: %s" % (path, oiio.geterror()))
    ok = out.write_image(np.ascontiguousarray(pixels))
    out.close()
    if not ok:
        raise BandError("cannot write %s" % path)


def check_mergeable(folder, stem):
    """BandError when the render applied something across rows (diffraction convolves the whole
    picture), which a merge by rows cannot reproduce."""
    from ..errors import DependencyError, MetadataError
    from ..metadata import read_metadata
    path = os.path.join(folder, stem + ".plenoptic.json")
    if os.path.exists(path):
        try:
            diffraction = read_metadata(path).diffraction
        except (MetadataError, DependencyError) as e:
            raise BandError("%s: %s" % (path, e)) from None
        if diffraction:
            raise BandError("the camera applies diffraction, which convolves across rows: its bands cannot be "
                            "merged into the image one render gives; render this data set without bands")


def merge(band_folders, rows, stem, extension, out_folder):
    """Merges the bands' files named <stem>... into out_folder."""
    names = sorted(os.listdir(band_folders[0]))
    for folder in band_folders[1:]:
        if sorted(os.listdir(folder)) != names:
            raise BandError("the bands wrote different files: %s vs %s" % (names, sorted(os.listdir(folder))))
    for name in names:
        if name in ("render.log", "band.json"):
            continue
        paths = [os.path.join(folder, name) for folder in band_folders]
        target = os.path.join(out_folder, name)
        if name == stem + extension or any(name == stem + suffix for suffix in ROW_SUFFIXES):
            spec, merged = _read(paths[0])
            for path, (first, last) in zip(paths[1:], rows[1:]):
                other_spec, pixels = _read(path)
                if pixels.shape != merged.shape:
                    raise BandError("%s: band images differ in size" % name)
                merged[first:last + 1] = pixels[first:last + 1]
            _write(target, spec, merged)
        else:
            with open(paths[0], "rb") as f:
                first_bytes = f.read()
            for path in paths[1:]:
                with open(path, "rb") as f:
                    if f.read() != first_bytes:
                        raise BandError("%s differs between bands (it should not depend on the rows)" % name)
            with open(target, "wb") as f:
                f.write(first_bytes)
