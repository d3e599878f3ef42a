# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode RAW [METADATA] [-o OUTDIR]: raw plenoptic render -> light field, sub-aperture
views, refocus sweep, epipolar-plane image and a contact sheet (docs/ground-truth.md).

Exit status 0 on success; 2 with one line 'plenoptic-decode: error: ...' on stderr when the
input or an option is refused (argparse's own usage errors too); 1 with one such line when
OpenImageIO, which reads every raw image, is not installed."""

from __future__ import annotations

import argparse
import math
import os
import re
import shutil
import sys
from typing import Sequence

import numpy as np

from .errors import DecodeError, DependencyError, MetadataError
from .hci import check_hci_camera, depth_map_path, export_hci
from .focus import default_slopes, slopes_from_depth_map
from .images import (check_encoding, inspect_raw, png_layout, read_depth_map, read_raw_image, read_stored,
                     require_openimageio, save_exr, save_png)
from .lightfield import decode, plan_decode
from .metadata import load_metadata, metadata_path_for
from .outputs import write_outputs
from .progress import Progress
from .total_focus import check_total_focus_camera, total_focus, virtual_depth_path
from .sensor import (check_white_is_not_the_raw, demosaic_bilinear, devignette, dn_to_linear, picture_reading,
                     white_reading)
from .contact_sheet import sheet_title


SLOPES_FORM = "START:STOP:COUNT (two numbers and a whole number >= 2, e.g. -0.8:0.8:17)"


def parse_slopes(text: str) -> np.ndarray:
    """--slopes START:STOP:COUNT -> the sweep's slopes (numpy.linspace(START, STOP, COUNT));
    ValueError with one sentence for the user, naming the option and the form."""
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        start, stop = float(parts[0]), float(parts[1])
        count = int(parts[2])
    except ValueError:
        raise ValueError("--slopes takes %s, found %r" % (SLOPES_FORM, text)) from None
    if count < 2 or not (math.isfinite(start) and math.isfinite(stop)) or start >= stop:
        raise ValueError("--slopes START:STOP:COUNT needs finite START < STOP and COUNT >= 2, found %r" % text)
    return np.linspace(start, stop, count)


_NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


def _attach_slopes_values(argv):
    """'--slopes -0.8:0.8:17' -> '--slopes=-0.8:0.8:17' (also for an abbreviation such as
    '--slo'): argparse would take a value that starts with '-' (and is not a plain negative
    number) for an option and stop with 'expected one argument'."""
    out = []
    i = 0
    while i < len(argv):
        arg = argv[i]
        if (len(arg) >= 4 and "--slopes".startswith(arg) and i + 1 < len(argv)
                and _NEGATIVE_VALUE.match(argv[i + 1])):
            out.append("--slopes=" + argv[i + 1])
            i += 2
            continue
        if arg == "--":
            out.extend(argv[i:])
            break
        out.append(arg)
        i += 1
    return out


def read_picture(path, meta, encoding, progress, white=False, raw=False, white_values=None, white_scale=None,
                 reading=None, announced=False):
    """The picture (H, W, 3) linear. What the file is comes from the options, its name in the
    metadata and its content (sensor.picture_reading, sensor.white_reading): the sensor's raw or
    a white image in DN through dn_to_linear and, for a mosaic, demosaic_bilinear; a linear white
    image as stored times its scale; the render's picture as its encoding says (`encoding`
    other than 'auto' is --encoding, which only a picture takes). `reading`: the decision already
    made (read_picture's checks without its reading); announced: its progress line was printed
    already (only the demosaicing is then reported)."""
    if reading is None:
        reading = (white_reading(meta, path, png_layout(path), white_values, white_scale) if white
                   else picture_reading(meta, path, png_layout(path), raw, encoding != "auto"))
    name = os.path.basename(path)
    if reading.warning:
        print("plenoptic-decode: warning: %s" % reading.warning, file=sys.stderr)
    if reading.kind == "dn":
        read_out = reading.read_out
        pixels = dn_to_linear(read_stored(path), read_out, path)
        if read_out.get("bayer"):
            progress.stage("%s: %s mosaic: demosaiced (bilinear)" % (name, read_out["bayer"]) if announced else
                           "%s: %s, %s mosaic: demosaiced (bilinear)" % (name, reading.why, read_out["bayer"]))
            return demosaic_bilinear(pixels[..., 0], read_out["bayer"])
        if not announced:
            progress.stage("%s: %s" % (name, reading.why))
        return np.ascontiguousarray(np.repeat(pixels[..., :1], 3, axis=2) if pixels.shape[2] == 1 else pixels[..., :3])
    if reading.kind == "linear":
        # A linear white image: value x 65535 / scale, grey or RGB.
        if not announced:
            progress.stage("%s: %s" % (name, reading.why))
        pixels = read_stored(path) * np.float32(reading.scale)
        return np.ascontiguousarray(np.repeat(pixels[..., :1], 3, axis=2) if pixels.shape[2] < 3 else pixels[..., :3])
    return read_raw_image(path, encoding)[0]


def _argument_parser():
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
    parser.add_argument("--slopes", default=None, metavar="START:STOP:COUNT",
                        help="refocus sweep in lenses per angular step, e.g. --slopes -0.8:0.8:17 (default: "
                             "the depths of the render's depth map if it wrote one, else the outermost "
                             "views shift by -2..+2 lenses; 9 steps)")
    parser.add_argument("--encoding", default="auto",
                        help="how the raw image's values encode light: auto (default: the file's own "
                             "encoding, e.g. a PNG's gAMA/sRGB chunk; linear for EXR), or an override: "
                             "srgb, linear, or a gamma number")
    parser.add_argument("--white", default=None, metavar="PNG",
                        help="devignette: divide the raw by this white image of the camera (its <stem>.white.png, "
                             "linear or in DN) where the white image carries light")
    parser.add_argument("--raw", dest="raw_dn", action="store_true",
                        help="RAW is the sensor's raw in DN (the render's <stem>.raw.png under any name): refused "
                             "unless its content can be (16-bit PNG, the read-out's channels and sBIT)")
    parser.add_argument("--microimages", default=None, metavar="CSV",
                        help="behind a traced prescription: the render's measured microimage centres (default: the "
                             "file the metadata's microimages.file names, beside the metadata, else "
                             "<metadata stem>.microimages.csv there)")
    parser.add_argument("--white-values", choices=("dn", "linear"), default=None,
                        help="with --white: the white image is in DN (through the metadata's read-out) or linear; "
                             "needed only when neither its name (the metadata's white_images) nor its content says")
    parser.add_argument("--white-scale", type=float, default=None, metavar="S",
                        help="with --white: a linear white image's scale (stored value x S = irradiance; the "
                             "metadata's white_images entry records it), for one renamed from the renderer's name")
    parser.add_argument("--hci", default=None, metavar="DIR",
                        help="write the HCI 4D light-field benchmark's layout to DIR instead of the usual outputs: "
                             "N x N views input_CamNNN.png, parameters.cfg, and the centre view's ground-truth "
                             "gt_depth_lowres.pfm and gt_disp_lowres.pfm from the render's depth map (plenoptic 1.0, "
                             "thin or thick_lens main lens; docs/hci-export.md). --angular N sets N (default: the "
                             "largest square that fits the microimage)")
    parser.add_argument("--hci-all-views", action="store_true",
                        help="with --hci: also write gt_depth_lowres_CamNNN.pfm and gt_disp_lowres_CamNNN.pfm for "
                             "every view")
    parser.add_argument("--total-focus", default=None, metavar="IMAGE",
                        help="write instead the total-focus (all-in-focus) image of a focused (2.0) raw to IMAGE "
                             "(.exr: linear float; otherwise 8-bit sRGB), from the render's virtual depth map "
                             "(depth_map on the camera) or --virtual-depth (docs/total-focus.md)")
    parser.add_argument("--virtual-depth", type=float, default=None, metavar="V",
                        help="with --total-focus: one virtual depth for the whole picture instead of the render's map")
    parser.add_argument("--total-focus-step", type=float, default=None, metavar="PX",
                        help="with --total-focus: picture pixels between output samples (default: one raw pixel "
                             "apart at the median virtual depth, about |v|)")
    parser.add_argument("--no-gif", action="store_true", help="do not write refocus.gif")
    parser.add_argument("--no-npy", action="store_true", help="do not write lightfield.npy")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress messages")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """The plenoptic-decode command; argv without the program name (default sys.argv[1:]).
    Returns the exit status."""
    args = _argument_parser().parse_args(_attach_slopes_values(sys.argv[1:] if argv is None else list(argv)))

    def fail(message, status=2):
        print("plenoptic-decode: error: %s" % message, file=sys.stderr)
        return status

    try:
        require_openimageio()
    except DependencyError as e:
        return fail(str(e), 1)
    if args.hci_all_views and not args.hci:
        return fail("--hci-all-views needs --hci DIR")
    if (args.virtual_depth is not None or args.total_focus_step is not None) and not args.total_focus:
        return fail("--virtual-depth and --total-focus-step need --total-focus IMAGE")
    if args.hci and args.total_focus:
        return fail("give --hci or --total-focus, not both")
    if args.virtual_depth is not None and not (math.isfinite(args.virtual_depth) and abs(args.virtual_depth) >= 1e-3):
        return fail("--virtual-depth must be a finite number other than 0, got %r" % args.virtual_depth)
    if not (args.step > 0 and math.isfinite(args.step)):
        return fail("--step must be a positive number of pixels")
    try:
        encoding = check_encoding(args.encoding)
    except ValueError:
        return fail("--encoding must be auto, srgb, linear or a positive gamma, found %r" % args.encoding)
    try:
        slopes = parse_slopes(args.slopes) if args.slopes is not None else None
    except ValueError as e:
        return fail(str(e))
    if (args.white_values is not None or args.white_scale is not None) and not args.white:
        return fail("--white-values and --white-scale need --white PNG")
    if args.white_scale is not None and not (math.isfinite(args.white_scale) and args.white_scale > 0):
        return fail("--white-scale must be a positive number, found %r" % args.white_scale)
    meta_path = args.metadata or metadata_path_for(args.raw)
    outdir = args.output or os.path.splitext(args.raw)[0] + ".lightfield"
    progress = Progress(not args.quiet)
    try:
        if not os.path.exists(args.raw):
            return fail("%s: the raw image does not exist" % args.raw)
        # Header, metadata and the light field's size first: nothing large is read or allocated
        # for an input that is refused.
        info = inspect_raw(args.raw, encoding)
        meta = load_metadata(meta_path, (info.width, info.height))
        if args.microimages is not None:
            if meta.lattice_is_exact:
                return fail("--microimages: this render's main lens is %s, behind which the decoder samples every "
                            "microimage around the metadata's microimage_lattice; measured centres are used behind "
                            "a traced prescription only" % meta.main_lens_type)
            if not os.path.isfile(args.microimages):
                return fail("--microimages %s: no such file" % args.microimages)
            meta.microimages_file = args.microimages
        if args.white:
            if not os.path.exists(args.white):
                return fail("%s: the white image does not exist" % args.white)
            check_white_is_not_the_raw(meta, args.raw, args.white)
        if args.hci:
            check_hci_camera(meta)
            depth_map_path(meta)
        elif args.total_focus:
            check_total_focus_camera(meta)
            if args.virtual_depth is None:
                virtual_depth_path(meta)
        else:
            plan_decode(meta, args.angular, args.step)
        # What the raw and the white image are (options, names, content), before reading either.
        reading = picture_reading(meta, args.raw, png_layout(args.raw), args.raw_dn, encoding != "auto")
        if args.white:
            white_read = white_reading(meta, args.white, png_layout(args.white), args.white_values, args.white_scale)
        # What the file is read as: a picture in its colour encoding, or values (DN, a linear white
        # image's) to which the file's encoding does not apply.
        if reading.kind == "picture":
            progress.stage("raw image %s: %s" % (os.path.basename(args.raw), info.describe()))
        else:
            progress.stage("raw image %s: %s, read as %s; the file's colour encoding is not used"
                           % (os.path.basename(args.raw), info.describe(encoding=False), reading.why))
        raw = read_picture(args.raw, meta, encoding, progress, reading=reading, announced=True)
        if args.white:
            white = read_picture(args.white, meta, encoding, progress, white=True, reading=white_read)
            raw = devignette(raw, white)
            progress.stage("devignetted with %s" % os.path.basename(args.white))
        if args.hci:
            n = export_hci(raw, meta, args.hci, args.angular, args.step, args.hci_all_views, progress)
            if not args.quiet:
                print("plenoptic-decode: wrote %d x %d views and their ground truth to %s" % (n, n, args.hci),
                      file=sys.stderr)
            return 0
        if args.total_focus:
            virtual = args.virtual_depth
            if virtual is None:
                path = virtual_depth_path(meta)
                virtual = read_depth_map(path)
                if virtual is None or virtual.shape != (meta.height, meta.width):
                    return fail("cannot read the virtual depth map %s as a %d x %d image" % (path, meta.width, meta.height))
            image, used = total_focus(raw, meta, virtual, args.total_focus_step)
            progress.stage("total focus: %d x %d samples %.3g px apart" % (image.shape[1], image.shape[0], used))
            if args.total_focus.lower().endswith(".exr"):
                save_exr(args.total_focus, image)
            else:
                save_png(args.total_focus, np.clip(image, 0, 1))
            if not args.quiet:
                print("plenoptic-decode: wrote %s" % args.total_focus, file=sys.stderr)
            return 0
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
        title = sheet_title(os.path.basename(args.raw), meta)
        sheet = write_outputs(raw, lf, outdir, slopes, gif=not args.no_gif, npy=not args.no_npy,
                              progress=progress, title=title)
        if args.contact_sheet:
            shutil.copyfile(sheet, args.contact_sheet)
            sheet = args.contact_sheet
    except MetadataError as e:
        return fail("%s: %s" % (meta_path, e))
    except DecodeError as e:
        return fail(str(e))
    except DependencyError as e:
        return fail(str(e), 1)
    except OSError as e:
        return fail("cannot write to %s: %s" % (outdir, e.strerror or e))
    if not args.quiet:
        print("plenoptic-decode: wrote %s" % sheet, file=sys.stderr)
    return 0
