# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode RAW [METADATA] [-o OUTDIR]: raw plenoptic render -> light field, sub-aperture
views, refocus sweep, epipolar-plane image and a contact sheet (docs/ground-truth.md).

Exit status 0 on success; 2 with one line 'plenoptic-decode: error: ...' on stderr when the
input or an option is refused (argparse's own usage errors too)."""

import argparse
import math
import os
import shutil
import sys

import numpy as np

from .errors import DecodeError, MetadataError
from .focus import default_slopes, slopes_from_depth_map
from .images import read_raw
from .lightfield import decode
from .metadata import load_metadata, metadata_path_for
from .outputs import write_outputs
from .progress import Progress


def parse_slopes(text):
    """--slopes LO:HI:COUNT -> the sweep's slopes; ValueError with the message for the user."""
    parts = text.split(":")
    if len(parts) != 3:
        raise ValueError("--slopes takes LO:HI:COUNT, e.g. -0.5:0.5:11")
    lo, hi, count = float(parts[0]), float(parts[1]), int(parts[2])
    if count < 2 or not (math.isfinite(lo) and math.isfinite(hi)) or lo >= hi:
        raise ValueError("--slopes needs LO < HI and COUNT >= 2")
    return np.linspace(lo, hi, count)


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
    return parser


def main(argv=None):
    """The plenoptic-decode command; argv without the program name (default sys.argv[1:]).
    Returns the exit status."""
    args = _argument_parser().parse_args(argv)

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
