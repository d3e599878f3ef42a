# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-dataset: render a data set described by a TOML spec, resumably, on this machine or
as a Slurm job array (docs/datasets.md).

    plenoptic-dataset run SPEC --out DIR [--executor local|slurm] [--bands N] [--povray PATH] [--replace] [-q]
    plenoptic-dataset items SPEC              the items and their declared values, one per line
    plenoptic-dataset task SPEC --out DIR --task K --tasks-file JSON   one Slurm array task (internal)

Exit status: 0 every item finished; 1 some item failed (each reported with its log; the others
were rendered); 2 a bad spec or option (one line naming the file, key and what is allowed), or
DIR holding another spec's data set (without --replace); 130 interrupted (finished items stay
finished; run again to resume). `items` piped into a command that stops reading (head) ends as
Unix tools do, by SIGPIPE, without a message."""

from __future__ import annotations

import argparse
import fcntl
import json
import os
import signal
import sys
from typing import Sequence

from ..locate import find_povray
from .runner import run_local
from .spec import SpecError, load_spec
from .store import OtherDataset, Store


def _parser():
    parser = argparse.ArgumentParser(prog="plenoptic-dataset",
                                     description="Render a data set of plenoptic raws with ground truth from a TOML spec.")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="render every item not yet finished (resumes an interrupted run)")
    run.add_argument("spec", help="the data set's TOML spec")
    run.add_argument("--out", required=True, metavar="DIR", help="the data set's folder")
    run.add_argument("--executor", choices=("local", "slurm"), default="local",
                     help="local: one item after the other on this machine (default); slurm: a Slurm job array")
    run.add_argument("--bands", type=int, default=None, metavar="N",
                     help="render each raw as N row bands (separate tasks on Slurm), merged by rows (default: the "
                          "spec's bands, else 1)")
    run.add_argument("--povray", default=None, help="the renderer (default: povray-plenoptic)")
    run.add_argument("--replace", action="store_true",
                     help="when DIR holds another spec's data set, make it this spec's: delete the items this spec "
                          "does not have, keep those it has (default: refuse)")
    run.add_argument("-q", "--quiet", action="store_true", help="no progress")
    items = commands.add_parser("items", help="list the items and their declared values")
    items.add_argument("spec")
    task = commands.add_parser("task", help="render one Slurm array task's items (used by the job script)")
    task.add_argument("spec")
    task.add_argument("--out", required=True, metavar="DIR")
    task.add_argument("--task", required=True, type=int, metavar="K")
    task.add_argument("--bands", type=int, default=None, metavar="N")
    task.add_argument("--povray", default=None)
    task.add_argument("--tasks-file", required=True, metavar="JSON", help="the submission's list of tasks")
    return parser


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    # kill, a closed terminal or Slurm's scancel stop the run as Ctrl-C does: POV-Ray (in its own
    # session) is stopped too, and no partial folder stays.
    for signum in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, _interrupt)

    def fail(message, status=2):
        print("plenoptic-dataset: error: %s" % message, file=sys.stderr)
        return status

    try:
        spec = load_spec(args.spec)
    except SpecError as e:
        return fail(str(e))
    if args.command == "items":
        # `items SPEC | head`: a reader that stops early ends the command as it ends Unix tools.
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
        for item in spec.items():
            print("%s %s" % (item.id, json.dumps(item.declares, sort_keys=True)))
        return 0
    bands = args.bands if args.bands is not None else spec.bands
    if not 1 <= bands <= spec.height:
        return fail("--bands must be a whole number from 1 to the image height (%d), got %d" % (spec.height, bands))
    try:
        povray = find_povray(args.povray)
    except FileNotFoundError as e:
        return fail(str(e))
    if args.command == "run":
        try:
            spec.check_reserved_words(povray)
        except SpecError as e:
            return fail(str(e))
    store = Store(args.out)
    try:
        if args.command == "task":
            from .slurm import run_task
            return run_task(store, spec, povray, args.task, bands, args.tasks_file)
        # One driver at a time per data set (tasks of a Slurm job take no lock).
        os.makedirs(store.root, exist_ok=True)
        lock = open(os.path.join(store.root, ".lock"), "w")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return fail("another plenoptic-dataset run is using %s" % store.root, 1)

        def jobs_running():
            from .slurm import SlurmError, _running_jobs
            try:
                return _running_jobs(store)
            except SlurmError:  # no Slurm here: no job either
                return []
        try:
            deleted = store.claim(spec, spec.items(), replace=args.replace, jobs_running=jobs_running)
        except OtherDataset as e:
            return fail(str(e))
        if deleted is not None and not args.quiet:
            print("plenoptic-dataset: replaced the data set in %s: deleted %d finished items of the other spec"
                  % (store.root, deleted), file=sys.stderr)
        if args.executor == "slurm":
            from .slurm import run_slurm
            finished, failures = run_slurm(store, spec, povray, bands, args.spec, quiet=args.quiet)
        else:
            from .slurm import SlurmError, _running_jobs
            try:
                running = _running_jobs(store)
            except SlurmError:  # no Slurm here: no job either
                running = []
            if running:
                return fail("job %s of this data set is still queued or running on Slurm: wait for it, or cancel "
                            "it with scancel, then run again" % " ".join(map(str, running)), 1)
            finished, failures = run_local(store, spec, povray, bands, quiet=args.quiet)
    except KeyboardInterrupt:
        print("\nplenoptic-dataset: interrupted; finished items are kept, run the same command again to resume",
              file=sys.stderr)
        return 130
    except OSError as e:
        return fail("%s: %s" % (getattr(e, "filename", None) or args.out, e.strerror or e), 1)
    except Exception as e:  # SlurmError: sbatch/squeue missing or refusing
        if type(e).__name__ != "SlurmError":
            raise
        return fail(str(e), 1)
    total = spec.item_count()
    if failures:
        print("plenoptic-dataset: %d of %d items finished, %d failed (logs in %s)"
              % (finished, total, len(failures), store.failed_dir), file=sys.stderr)
        return 1
    if not args.quiet:
        print("plenoptic-dataset: %d of %d items finished; manifest %s" % (finished, total, store.manifest),
              file=sys.stderr)
    return 0
