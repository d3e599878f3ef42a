# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode RAW [METADATA] [-o OUTDIR]: raw plenoptic render -> light field, sub-aperture
views, refocus sweep, epipolar-plane image and a contact sheet (docs/ground-truth.md).

Exit status 0 on success; 2 with one line 'plenoptic-decode: error: ...' on stderr when the
input or an option is refused (argparse's own usage errors too); 1 with one such line when
OpenImageIO, which reads every raw image, is not installed."""

import argparse
import math
import os
import re
import shutil
import sys

import numpy as np

from .errors import DecodeError, DependencyError, MetadataError
from .focus import default_slopes, slopes_from_depth_map
from .images import check_encoding, inspect_raw, read_raw_image, require_openimageio
from .lightfield import decode, plan_decode
from .metadata import load_metadata, metadata_path_for
from .outputs import write_outputs
from .progress import Progress


SLOPES_FORM = "START:STOP:COUNT (two numbers and a whole number >= 2, e.g. -0.8:0.8:17)"


def parse_slopes(text):
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
    parser.add_argument("--no-gif", action="store_true", help="do not write refocus.gif")
    parser.add_argument("--no-npy", action="store_true", help="do not write lightfield.npy")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress messages")
    return parser


def main(argv=None):
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
    meta_path = args.metadata or metadata_path_for(args.raw)
    outdir = args.output or os.path.splitext(args.raw)[0] + ".lightfield"
    progress = Progress(not args.quiet)
    try:
        if not os.path.exists(args.raw):
            return fail("%s: the raw image does not exist" % args.raw)
        # Header, metadata and the light field's size first: nothing large is read or allocated
        # for an input that is refused.
        info = inspect_raw(args.raw, encoding)
        progress.stage("raw image %s: %s" % (os.path.basename(args.raw), info.describe()))
        meta = load_metadata(meta_path, (info.width, info.height))
        plan_decode(meta, args.angular, args.step)
        raw, _ = read_raw_image(args.raw, encoding)
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
    except DependencyError as e:
        return fail(str(e), 1)
    except OSError as e:
        return fail("cannot write to %s: %s" % (outdir, e.strerror or e))
    if not args.quiet:
        print("plenoptic-decode: wrote %s" % sheet, file=sys.stderr)
    return 0
