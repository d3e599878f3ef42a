# SPDX-License-Identifier: AGPL-3.0-or-later
"""The Slurm executor: the items (or their row bands) not yet finished become one job array
(sbatch --array), each array task renders its share with `plenoptic-dataset task`, and the
submitting command waits, showing progress, then merges bands, verifies every item and writes
the manifest. Running it again submits only what is still missing."""

import json
import os
import shlex
import subprocess
import sys
import time

from .bands import band_rows
from .runner import (ItemFailed, ItemProgress, band_dir, band_record, merge_item, render_band, run_item)

POLL_SECONDS = 2.0


class SlurmError(Exception):
    pass


def _run(cmd):
    try:
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    except FileNotFoundError:
        raise SlurmError("%s is not installed (Debian: apt install slurm-client; a local test cluster: "
                         "tools/slurm-local start)" % cmd[0]) from None
    except subprocess.TimeoutExpired:
        raise SlurmError("%s did not answer within 60 s" % " ".join(cmd)) from None
    if run.returncode != 0:
        raise SlurmError("%s failed: %s" % (" ".join(cmd), (run.stderr or run.stdout).strip()))
    return run.stdout


def _slurm_dir(store):
    return os.path.join(store.root, "slurm")


def _queued(job_ids):
    """{array job id: [(task id, state)]} of these jobs that Slurm still lists (queued, running or
    completing). Asks for the user's jobs rather than for the ids: Slurm forgets finished jobs
    after a while (MinJobAge), and squeue -j refuses an id it has forgotten."""
    import getpass
    out = _run(["squeue", "-h", "-o", "%F %i %T", "-u", getpass.getuser()])
    listed = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0].isdigit() and int(parts[0]) in job_ids:
            listed.setdefault(int(parts[0]), []).append((parts[1], parts[2]))
    return listed


def _running_jobs(store):
    """The data set's jobs Slurm still lists."""
    try:
        with open(os.path.join(_slurm_dir(store), "jobs.json")) as f:
            jobs = json.load(f)
    except (OSError, ValueError):
        return []
    return sorted(_queued(set(jobs))) if jobs else []


def _item_finished(store, spec, item, bands):
    """Whether the item, or every band of it, is finished (a cheap check for progress)."""
    if os.path.exists(os.path.join(store.item_dir(item.id), "item.json")):
        return True
    if bands <= 1:
        return False
    return all(os.path.exists(os.path.join(band_dir(store, item.id, k), "band.json"))
               for k in range(len(band_rows(spec.height, bands))))


def _tasks(store, spec, bands, done):
    """The work still missing, as array tasks: lists of [item index, band or -1]."""
    per_task = max(1, spec.slurm.get("items_per_task", 1))
    units = []
    for item in spec.items():
        if item.id in done:
            continue
        if bands <= 1:
            units.append([item.index, -1])
            continue
        for k, rows in enumerate(band_rows(spec.height, bands)):
            record = band_record(band_dir(store, item.id, k))
            if record is None or record.get("rows") != list(rows):
                units.append([item.index, k])
    return [units[i:i + per_task] for i in range(0, len(units), per_task)]


def job_script(store, spec, spec_path, povray, bands, tasks_file):
    """The sbatch script: resources from the spec's [slurm], one array task per entry of tasks_file."""
    slurm = spec.slurm
    logs = os.path.join(_slurm_dir(store), "logs")
    lines = ["#!/bin/sh", "#SBATCH --job-name=plenoptic-dataset", "#SBATCH --output=%s/%%A_%%a.out" % logs]
    if "partition" in slurm:
        lines.append("#SBATCH --partition=%s" % slurm["partition"])
    if "cpus_per_task" in slurm:
        lines.append("#SBATCH --cpus-per-task=%d" % slurm["cpus_per_task"])
    if "mem" in slurm:
        lines.append("#SBATCH --mem=%s" % slurm["mem"])
    if "time" in slurm:
        lines.append("#SBATCH --time=%s" % slurm["time"])
    for extra in slurm.get("extra", []):
        lines.append("#SBATCH %s" % extra)
    package_parent = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    command = [sys.executable, "-m", "plenoptic_lf.dataset", "task", os.path.abspath(spec_path), "--out", store.root,
               "--task", "$SLURM_ARRAY_TASK_ID", "--bands", str(bands), "--povray", povray, "--tasks-file", tasks_file]
    lines.append("export PYTHONPATH=%s${PYTHONPATH:+:$PYTHONPATH}" % shlex.quote(package_parent))
    lines.append("exec " + " ".join(c if c == "$SLURM_ARRAY_TASK_ID" else shlex.quote(c) for c in command))
    return "\n".join(lines) + "\n"


def run_task(store, spec, povray, task, bands, tasks_file):
    """One array task: renders its items or bands; exit status 0, or 1 when one failed."""
    with open(tasks_file) as f:
        tasks = json.load(f)
    if not 0 <= task < len(tasks):
        print("plenoptic-dataset: task %d of %d does not exist" % (task, len(tasks)), file=sys.stderr)
        return 2
    status = 0
    for index, band in tasks[task]:
        item = spec.item(index)
        try:
            if band < 0:
                run_item(store, spec, item, povray, 1)
            else:
                render_band(store, spec, item, povray, band, band_rows(spec.height, bands)[band])
        except ItemFailed as failure:
            print("plenoptic-dataset: %s\n    (log: %s)" % (failure, failure.log_path), file=sys.stderr)
            status = 1
    return status


def run_slurm(store, spec, povray, bands, spec_path, quiet=False):
    """Submits what is missing as a job array, waits with progress, merges bands, verifies and
    writes the manifest: (finished count, [ItemFailed])."""
    store.create()
    running = _running_jobs(store)
    if running:
        raise SlurmError("job %s of this data set is still queued or running: wait for it, or cancel it with "
                         "scancel %s, then run again" % (running[0], " ".join(map(str, running))))
    store.clear_partials()
    items = spec.items()
    done = store.finished(items)
    tasks = _tasks(store, spec, bands, done)
    progress = ItemProgress(len(items), len(done), enabled=not quiet)
    folder = _slurm_dir(store)
    os.makedirs(os.path.join(folder, "logs"), exist_ok=True)
    job = None
    if tasks:
        stamp = time.strftime("%Y%m%d-%H%M%S")
        tasks_file = os.path.join(folder, "tasks-%s.json" % stamp)
        with open(tasks_file, "w") as f:
            json.dump(tasks, f)
        script = os.path.join(folder, "job-%s.sh" % stamp)
        with open(script, "w") as f:
            f.write(job_script(store, spec, spec_path, povray, bands, tasks_file))
        array = "0-%d" % (len(tasks) - 1)
        if "max_parallel" in spec.slurm:
            array += "%%%d" % spec.slurm["max_parallel"]
        job = int(_run(["sbatch", "--parsable", "--array=" + array, script]).strip().split(";")[0])
        with open(os.path.join(folder, "jobs.json"), "w") as f:
            json.dump([job], f)
        progress.message("plenoptic-dataset: submitted job %d: %d array tasks for %d items%s"
                         % (job, len(tasks), len(items) - len(done), " in %d bands" % bands if bands > 1 else ""))
    try:
        while job is not None:
            listed = _queued({job})
            progress.done = sum(1 for item in items if item.id not in done and _item_finished(store, spec, item, bands))
            progress.show()
            if not listed:
                break
            time.sleep(POLL_SECONDS)
    except KeyboardInterrupt:
        if job is not None:
            subprocess.run(["scancel", str(job)], capture_output=True)
            progress.message("plenoptic-dataset: cancelled job %d" % job)
        raise
    finally:
        progress.close()
    # Collect: merge bands, verify, write the manifest; report what is missing.
    failures = []
    records = []
    for item in items:
        record = store.record(item.id)
        if record is None and bands > 1 and all(
                band_record(band_dir(store, item.id, k)) is not None for k in range(len(band_rows(spec.height, bands)))):
            try:
                record = merge_item(store, spec, item, bands)
            except ItemFailed as failure:
                failures.append(failure)
                continue
        if record is None:
            log = os.path.join(store.failed_dir, item.id + ".log")
            if not os.path.exists(log):
                log = _task_log(store, job, tasks, item.index)
            failures.append(ItemFailed("item %s did not finish" % item.id, log))
            continue
        records.append(record)
    store.write_manifest(records)
    for failure in failures:
        print("plenoptic-dataset: %s\n    (log: %s)" % (failure, failure.log_path), file=sys.stderr)
    return len(records), failures


def _task_log(store, job, tasks, index):
    """The Slurm output file of the array task that had item `index` (a task killed before it
    wrote the item's own log)."""
    for k, units in enumerate(tasks):
        if any(unit[0] == index for unit in units):
            return os.path.join(_slurm_dir(store), "logs", "%s_%d.out" % (job, k))
    return os.path.join(_slurm_dir(store), "logs")
