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
    out = _run(["squeue", "-h", "--me", "-o", "%F %i %T %r"])
    listed = {}
    for line in out.splitlines():
        parts = line.split(None, 3)
        if len(parts) >= 3 and parts[0].isdigit() and int(parts[0]) in job_ids:
            listed.setdefault(int(parts[0]), []).append((parts[1], parts[2], parts[3] if len(parts) > 3 else ""))
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
    """The work still missing, as array tasks: lists of [item index, item id, band or -1]. The id
    lets a task refuse work whose spec or scene changed after the submission."""
    per_task = max(1, spec.slurm.get("items_per_task", 1))
    units = []
    for item in spec.items():
        if item.id in done:
            continue
        if bands <= 1:
            units.append([item.index, item.id, -1])
            continue
        for k, rows in enumerate(band_rows(spec.height, bands)):
            record = band_record(band_dir(store, item.id, k))
            if record is None or record.get("rows") != list(rows):
                units.append([item.index, item.id, k])
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
    for index, item_id, band in tasks[task]:
        if index >= spec.item_count() or spec.item(index).id != item_id:
            print("plenoptic-dataset: item %s: the spec or its scene changed since the job was submitted; run "
                  "plenoptic-dataset again to submit the changed items" % item_id, file=sys.stderr)
            status = 1
            continue
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
    jobs = []  # (job id, tasks of that array)
    try:
        if tasks:
            limit = _max_array_size()
            stamp = time.strftime("%Y%m%d-%H%M%S")
            for part, start in enumerate(range(0, len(tasks), limit)):
                chunk = tasks[start:start + limit]
                tasks_file = os.path.join(folder, "tasks-%s-%d.json" % (stamp, part))
                with open(tasks_file, "w") as f:
                    json.dump(chunk, f)
                script = os.path.join(folder, "job-%s-%d.sh" % (stamp, part))
                with open(script, "w") as f:
                    f.write(job_script(store, spec, spec_path, povray, bands, tasks_file))
                array = "0-%d" % (len(chunk) - 1)
                if "max_parallel" in spec.slurm:
                    array += "%%%d" % spec.slurm["max_parallel"]
                job = int(_run(["sbatch", "--parsable", "--array=" + array, script]).strip().split(";")[0])
                jobs.append((job, chunk))
                with open(os.path.join(folder, "jobs.json"), "w") as f:
                    json.dump([j for j, _ in jobs], f)
            progress.message("plenoptic-dataset: submitted job%s %s: %d array tasks for %d items%s"
                             % ("s" if len(jobs) > 1 else "", ", ".join(str(j) for j, _ in jobs), len(tasks),
                                len(items) - len(done), " in %d bands" % bands if bands > 1 else ""))
        failed_polls, reason_shown = 0, None
        while jobs:
            try:
                listed = _queued({j for j, _ in jobs})
                failed_polls = 0
            except SlurmError as e:  # slurmctld busy or restarting: try again, give up after a minute
                failed_polls += 1
                if failed_polls * POLL_SECONDS > 60:
                    raise SlurmError("%s; the job%s %s may still run: run plenoptic-dataset again when it has "
                                     "ended, or cancel it" % (e, "s" if len(jobs) > 1 else "",
                                                               " ".join(str(j) for j, _ in jobs))) from None
                time.sleep(POLL_SECONDS)
                continue
            progress.done = sum(1 for item in items if item.id not in done and _item_finished(store, spec, item, bands))
            progress.show()
            if not listed:
                break
            states = [entry for entries in listed.values() for entry in entries]
            if all(state == "PENDING" for _, state, _ in states):
                reason = states[0][2]
                if reason and reason != reason_shown and reason not in ("None", "Priority", "Resources",
                                                                        "JobArrayTaskLimit"):
                    progress.message("plenoptic-dataset: the job waits: %s (squeue's reason)" % reason)
                    reason_shown = reason
            time.sleep(POLL_SECONDS)
    except KeyboardInterrupt:
        for job, _ in jobs:
            subprocess.run(["scancel", str(job)], capture_output=True)
        if jobs:
            progress.message("plenoptic-dataset: cancelled job%s %s" % ("s" if len(jobs) > 1 else "",
                                                                        " ".join(str(j) for j, _ in jobs)))
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
                log = _task_log(store, jobs, item.index)
            failures.append(ItemFailed("item %s did not finish" % item.id, log))
            continue
        records.append(record)
    store.write_manifest(records)
    for failed in failures:
        print("plenoptic-dataset: %s\n    (log: %s)" % (failed, failed.log_path), file=sys.stderr)
    return len(records), failures


def _task_log(store, jobs, index):
    """The Slurm output file of the array task that had item `index` (a task killed before it
    wrote the item's own log)."""
    for job, tasks in jobs:
        for k, units in enumerate(tasks):
            if any(unit[0] == index for unit in units):
                return os.path.join(_slurm_dir(store), "logs", "%s_%d.out" % (job, k))
    return os.path.join(_slurm_dir(store), "logs")


def _max_array_size():
    """Slurm's MaxArraySize less one (array indices run from 0 to MaxArraySize - 1); 1000 when
    scontrol cannot tell."""
    try:
        out = _run(["scontrol", "show", "config"])
    except SlurmError:
        return 1000
    for line in out.splitlines():
        if line.strip().startswith("MaxArraySize"):
            value = line.split("=", 1)[1].strip()
            if value.isdigit() and int(value) > 1:
                return int(value) - 1
    return 1000
