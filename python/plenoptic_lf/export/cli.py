# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-export RENDER --to FORMAT DIR: a render's image and ground truth in a layout another
tool reads (docs/export/README.md). RENDER is the rendered image; its metadata
(<stem>.plenoptic.json) sits beside it, as plenoptic-decode takes it.

The files are written into a staging folder beside DIR and moved into DIR (each with one
rename) only when the whole export succeeded: a refusal, an error or Ctrl-C leaves DIR as it
was, with no half-written file.

Exit status 0 on success; 2 with one line 'plenoptic-export: error: ...' on stderr when the input,
the format or an option is refused (argparse's usage errors too); 1 when a module the tools need
(OpenImageIO) is missing; 130 when interrupted."""

from __future__ import annotations

import argparse
import math
import os
import shutil
import signal
import sys
import tempfile
from pathlib import Path
from typing import Any, Sequence

from ..errors import DecodeError, DependencyError, MetadataError
from ..images import check_encoding, require_openimageio
from ..metadata import metadata_path_for
from ..progress import Progress
from . import FORMATS, ExportError, Render

PROG = "plenoptic-export"


def _format_list() -> str:
    if not FORMATS:
        return "(none in this build)"
    return "\n".join("  %-8s %s" % (name, FORMATS[name].SUMMARY) for name in sorted(FORMATS))


def _argument_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG, formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Write a plenoptic render (its image and ground truth) in a layout another tool reads.",
        epilog="formats:\n%s\n\nThe files appear in DIR only when the whole export succeeded. docs/export/README.md "
               "describes each format, what its reader expects, and what it refuses." % _format_list())
    parser.add_argument("render", metavar="RENDER",
                        help="the rendered image (PNG, EXR, ...); its metadata <stem>.plenoptic.json beside it")
    parser.add_argument("--to", dest="format", required=True, metavar="FORMAT",
                        help="the format: %s" % (", ".join(sorted(FORMATS)) or "none in this build"))
    parser.add_argument("out_dir", metavar="DIR", help="the folder to write into (made if missing)")
    parser.add_argument("--metadata", default=None, metavar="JSON",
                        help="the render's metadata (default: <RENDER stem>.plenoptic.json beside it)")
    parser.add_argument("--angular", type=int, default=None, metavar="N",
                        help="formats that decode views: angular samples per axis (odd; default: the decoder's)")
    parser.add_argument("--step", type=float, default=None, metavar="PX",
                        help="formats that decode views: angular sample spacing in raw pixels (default 1)")
    parser.add_argument("--encoding", default="auto",
                        help="how the image's values encode light, as plenoptic-decode --encoding (default auto)")
    parser.add_argument("-O", "--option", dest="options", action="append", default=[], metavar="NAME=VALUE",
                        help="an option of the format (see docs/export/README.md), repeatable")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress messages")
    return parser


def _format_options(module: Any, name: str, args: argparse.Namespace) -> dict[str, Any]:
    """The options for module.export from --angular, --step and -O NAME=VALUE; ExportError for an
    option the format does not take (naming those it does)."""
    allowed = dict(getattr(module, "OPTIONS", {}))
    given: dict[str, Any] = {}
    if args.angular is not None:
        given["angular"] = args.angular
    if args.step is not None:
        if not (math.isfinite(args.step) and args.step > 0):
            raise ExportError("--step must be a positive number of pixels, found %r" % args.step)
        given["step"] = args.step
    for text in args.options:
        key, sep, value = text.partition("=")
        if not sep or not key:
            raise ExportError("-O takes NAME=VALUE, found %r" % text)
        if key in given:
            raise ExportError("option %r given twice" % key)
        given[key] = value
    for key in given:
        if key not in allowed:
            flag = "--" + key if key in ("angular", "step") else "-O " + key
            raise ExportError("%s: the format %s takes %s" % (
                flag, name, "no options" if not allowed else "only " + ", ".join(
                    ("--" + k if k in ("angular", "step") else "-O " + k) for k in sorted(allowed))))
    return given


def _staging_dir(out_dir: str) -> str:
    """A fresh folder beside out_dir (the same file system, so each file moves with one rename)."""
    target = os.path.abspath(out_dir)
    parent = os.path.dirname(target)
    os.makedirs(parent, exist_ok=True)
    return tempfile.mkdtemp(prefix=".%s.partial-" % os.path.basename(target), dir=parent)


def _publish(staging: str, out_dir: str, written: Sequence[Path]) -> list[Path]:
    """Moves every file of the staging folder into out_dir (os.replace: atomic per file); the
    files the format reported, as they are now named."""
    staging_path = Path(staging).resolve()
    reported = []
    for path in written:
        real = Path(path).resolve()
        if staging_path not in real.parents or not real.is_file():
            raise RuntimeError("the exporter reported %s, not a file it wrote into its folder" % path)
        reported.append(real.relative_to(staging_path))
    os.makedirs(out_dir, exist_ok=True)
    for folder, _, files in os.walk(staging):
        relative = os.path.relpath(folder, staging)
        target_folder = os.path.normpath(os.path.join(out_dir, relative))
        os.makedirs(target_folder, exist_ok=True)
        for name in sorted(files):
            os.replace(os.path.join(folder, name), os.path.join(target_folder, name))
    return [Path(out_dir) / r for r in reported]


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def main(argv: Sequence[str] | None = None) -> int:
    """The plenoptic-export command; argv without the program name (default sys.argv[1:])."""
    args = _argument_parser().parse_args(sys.argv[1:] if argv is None else list(argv))

    def fail(message: str, status: int = 2) -> int:
        print("%s: error: %s" % (PROG, message), file=sys.stderr)
        return status

    if args.format not in FORMATS:
        return fail("--to %s: no such format; the formats are %s" % (
            args.format, ", ".join(sorted(FORMATS)) or "(none in this build)"))
    module = FORMATS[args.format]
    try:
        encoding = check_encoding(args.encoding)
    except ValueError:
        return fail("--encoding must be auto, srgb, linear or a positive gamma, found %r" % args.encoding)
    try:
        options = _format_options(module, args.format, args)
    except ExportError as e:
        return fail(str(e))
    try:
        require_openimageio()
    except DependencyError as e:
        return fail(str(e), 1)
    if os.path.exists(args.out_dir) and not os.path.isdir(args.out_dir):
        return fail("%s: exists and is not a folder" % args.out_dir)

    previous = signal.signal(signal.SIGTERM, _interrupt) if hasattr(signal, "SIGTERM") else None
    progress = Progress(not args.quiet, PROG)
    staging = None
    meta_path = args.metadata or metadata_path_for(args.render)
    try:
        render = Render(args.render, meta_path, encoding, progress)
        staging = _staging_dir(args.out_dir)
        written = module.export(render, Path(staging), **options)
        files = _publish(staging, args.out_dir, written)
    except KeyboardInterrupt:
        print("%s: interrupted: nothing written to %s" % (PROG, args.out_dir), file=sys.stderr)
        return 130
    except MetadataError as e:
        return fail("%s: %s" % (meta_path, e))
    except DecodeError as e:  # ExportError too
        return fail(str(e))
    except DependencyError as e:
        return fail(str(e), 1)
    except OSError as e:
        return fail("cannot write %s: %s" % (getattr(e, "filename", None) or args.out_dir, e.strerror or e))
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    for path in files:
        print(path)
    if not args.quiet:
        print("%s: wrote %d file%s (%s) to %s" % (PROG, len(files), "" if len(files) == 1 else "s", args.format,
                                                  args.out_dir), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
