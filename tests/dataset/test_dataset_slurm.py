# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-dataset --executor slurm on a real (one-node) Slurm cluster: tools/slurm-local
starts Debian's slurmctld, slurmd and munged for the test and stops them after it (nothing of it
left running). A sweep of 4 items, one of them slow, in 2 row bands: the slow item's array task
is killed mid-run (scancel), the run reports that item with its log and exits 1; the same
command again submits only what is missing and finishes; every item equals, pixel for pixel,
the local executor's render of it."""

import json
import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

from plenoptic_testing.datasets import check_manifest, pixels, write_spec


@pytest.fixture(scope="module")
def cluster(args):
    tool = os.path.join(args.tools, "slurm-local")
    state = os.path.join(args.work, "slurm-local")
    env = dict(os.environ, SLURM_LOCAL_DIR=state)
    start = subprocess.run([tool, "start"], capture_output=True, text=True, env=env, timeout=120)
    assert start.returncode == 0, "tools/slurm-local start: %s" % (start.stdout + start.stderr)
    conf = start.stdout.strip().split("=", 1)[1]
    yield dict(os.environ, SLURM_CONF=conf)
    stop = subprocess.run([tool, "stop"], capture_output=True, text=True, env=env, timeout=120)
    left = [name for name in ("slurmctld", "slurmd", "slurmstepd", "munged")
            if subprocess.run(["pgrep", "-x", name], capture_output=True).returncode == 0]
    assert stop.returncode == 0 and not left, (
        "tools/slurm-local stop leaves nothing running (%s; still: %s)" % (stop.stderr, left))


def squeue(env, job):
    out = subprocess.run(["squeue", "-h", "-o", "%i %T", "-j", str(job)], capture_output=True, text=True, env=env)
    return [line.split() for line in out.stdout.splitlines()]


def test_sweep_on_slurm_with_a_killed_task(args, cluster):
    work = os.path.join(args.work, "slurm")
    shutil.rmtree(work, ignore_errors=True)
    # Item 3 renders slowly (4000 samples), so that its tasks can be caught running.
    spec = write_spec(work, "sweep", focus="[1.0, 1.5]", extra='povray_options = ["Declare=Slow_Item=3"]')
    slow_index = {3}

    out = os.path.join(work, "out")
    env = dict(cluster, PYTHONPATH=args.python, PLENOPTIC_POVRAY=args.povray)
    cmd = [sys.executable, "-m", "plenoptic_lf.dataset", "run", spec, "--out", out, "--executor", "slurm", "--bands", "2"]
    driver = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, env=env)
    # Wait for the job, then for a task of a slow item to run, and kill that task.
    jobs_file = os.path.join(out, "slurm", "jobs.json")
    deadline = time.monotonic() + 120
    killed = None
    while time.monotonic() < deadline and killed is None:
        time.sleep(0.5)
        if not os.path.exists(jobs_file):
            continue
        with open(jobs_file) as f:
            job = json.load(f)[0]
        tasks_file = sorted(n for n in os.listdir(os.path.join(out, "slurm")) if n.startswith("tasks-"))[-1]
        with open(os.path.join(out, "slurm", tasks_file)) as f:
            tasks = json.load(f)
        for task_id, state in squeue(env, job):
            k = int(task_id.split("_")[1]) if "_" in task_id and task_id.split("_")[1].isdigit() else None
            if state == "RUNNING" and k is not None and any(unit[0] in slow_index for unit in tasks[k]):
                time.sleep(1.0)  # mid-run
                subprocess.run(["scancel", task_id], env=env, check=True)
                killed = task_id
                break
    assert killed, "a slow item's task was seen running and killed"
    _, err = driver.communicate(timeout=600)
    assert driver.returncode == 1 and "did not finish" in err and "log:" in err, (
        "the run reports the killed task's item and exits 1 (exit %s: %s)" % (driver.returncode, err[-2000:]))

    again = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=900)
    assert again.returncode == 0, "the same command again finishes the data set (%s)" % again.stderr[-2000:]
    submitted = [line for line in again.stderr.splitlines() if "submitted job" in line]
    assert submitted and "array tasks for 1 items" in submitted[0], (
        "only the killed item is submitted again: %s" % submitted)
    records = check_manifest(out, 4)
    assert all(len(r["bands"]) == 2 for r in records.values()), "every item rendered in 2 bands"
    assert not os.path.exists(os.path.join(out, "bands")), "no band left unmerged"

    local = os.path.join(work, "local")
    run = subprocess.run([sys.executable, "-m", "plenoptic_lf.dataset", "run", spec, "--out", local, "-q"],
                         capture_output=True, text=True, env=env, timeout=900)
    assert run.returncode == 0, run.stderr
    for item_id, record in records.items():
        for name in record["files"]:
            if name.endswith((".png", ".exr")):
                assert np.array_equal(pixels(os.path.join(out, "items", item_id, name)),
                                      pixels(os.path.join(local, "items", item_id, name))), (
                    "%s/%s: Slurm's merged bands = the local render" % (item_id, name))
