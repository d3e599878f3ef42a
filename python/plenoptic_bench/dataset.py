# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section dataset: what plenoptic-dataset costs per item, run by itself on this
machine and through Slurm (tools/slurm-local's one-node cluster), against the same POV-Ray
commands run bare one after the other; and a raw split into row bands against one render."""
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

from plenoptic_lf.povray import run_povray

from .util import ROOT, log

PYTHON = os.path.join(ROOT, "python")
SCENE = os.path.join(ROOT, "scenes", "dataset_demo.pov")


def _spec(path, width, height, samples, count, bands=1, slurm_cpus=None, per_task=1):
    text = ('scene = "%s"\nwidth = %d\nheight = %d\nbands = %d\n[options]\nsamples = %d\ndepth_map = true\n'
            '[random]\ncount = %d\nseed = 3\nSphere_X = { uniform = [-0.05, 0.05] }\n'
            % (SCENE, width, height, bands, samples, count))
    if slurm_cpus:
        text += '[slurm]\ncpus_per_task = %d\nitems_per_task = %d\n' % (slurm_cpus, per_task)
    with open(path, "w") as f:
        f.write(text)
    return path


def _dataset(povray, argv, env=None):
    env = dict(os.environ if env is None else env, PYTHONPATH=PYTHON, PLENOPTIC_POVRAY=povray)
    start = time.perf_counter()
    run = subprocess.run([sys.executable, "-m", "plenoptic_lf.dataset"] + argv + ["-q"], capture_output=True,
                         text=True, env=env)
    if run.returncode != 0:
        raise RuntimeError("plenoptic-dataset failed: %s" % run.stderr[-2000:])
    return time.perf_counter() - start


def _bare(povray, out, spec_path):
    """The items' own POV-Ray commands (from their records), run again one after the other."""
    with open(os.path.join(out, "manifest.jsonl")) as f:
        records = [json.loads(line) for line in f]
    folder = os.path.join(os.path.dirname(out), "bare")
    os.makedirs(folder, exist_ok=True)
    start = time.perf_counter()
    for record in records:
        cmd = [a if not a.startswith("+O") else "+O" + os.path.join(folder, record["image"]) for a in record["command"]]
        run = run_povray(cmd, cwd=folder)
        if not run.ok:
            raise RuntimeError("povray failed (exit %d): %s\n%s" % (run.returncode, " ".join(cmd), run.output[-1500:]))
    return time.perf_counter() - start, len(records)


def _slurm_env(work):
    tool = os.path.join(ROOT, "tools", "slurm-local")
    env = dict(os.environ, SLURM_LOCAL_DIR=os.path.join(work, "slurm-local"))
    start = subprocess.run([tool, "start"], capture_output=True, text=True, env=env)
    if start.returncode != 0:
        log("dataset: no Slurm cluster (%s); the Slurm rows are skipped" % start.stderr.strip().splitlines()[-1:])
        return None, None
    return dict(env, SLURM_CONF=start.stdout.strip().split("=", 1)[1]), (lambda: subprocess.run([tool, "stop"], env=env,
                                                                                                    capture_output=True))


def section_dataset(b, quick, runs, results):
    work = os.path.join(b.work, "dataset")
    os.makedirs(work, exist_ok=True)
    count = 4 if quick else 24
    size = (64, 48) if quick else (160, 120)
    samples = 4
    rows = []
    env, stop = (None, None) if quick else _slurm_env(work)
    try:
        for r in range(1 if quick else runs):
            spec = _spec(os.path.join(work, "items.toml"), size[0], size[1], samples, count)
            local_out = os.path.join(work, "local-%d" % r)
            local = _dataset(b.povray, ["run", spec, "--out", local_out])
            bare, n = _bare(b.povray, local_out, spec)
            row = {"run": r, "items": n, "bare_s": bare, "local_s": local}
            if env is not None:
                slurm_spec = _spec(os.path.join(work, "items_slurm.toml"), size[0], size[1], samples, count,
                                   slurm_cpus=os.cpu_count())
                row["slurm_s"] = _dataset(b.povray, ["run", slurm_spec, "--out", os.path.join(work, "slurm-%d" % r),
                                                     "--executor", "slurm"], env)
                chunked_spec = _spec(os.path.join(work, "items_slurm6.toml"), size[0], size[1], samples, count,
                                     slurm_cpus=os.cpu_count(), per_task=6)
                row["slurm6_s"] = _dataset(b.povray, ["run", chunked_spec, "--out", os.path.join(work, "slurm6-%d" % r),
                                                      "--executor", "slurm"], env)
            rows.append(row)
            log("  dataset run %d: %d items: bare %.2f s, local %.2f s%s" % (
                r, n, bare, local, ", Slurm %.2f s, 6 items a task %.2f s" % (row["slurm_s"], row["slurm6_s"])
                if "slurm_s" in row else ""))
            for folder in ("bare", "local-%d" % r, "slurm-%d" % r, "slurm6-%d" % r):
                shutil.rmtree(os.path.join(work, folder), ignore_errors=True)
        per_item = {key: statistics.median(row[key] / row["items"] for row in rows)
                    for key in ("bare_s", "local_s", "slurm_s", "slurm6_s") if all(key in row for row in rows)}
        results["dataset"] = {"items": count, "size": list(size), "samples": samples, "runs": rows,
                              "per_item_s": per_item}
        # One larger raw, whole and in 4 bands (the local executor renders the bands one after the
        # other; on Slurm they would run at once on 4 nodes).
        big = (240, 180) if quick else (1440, 1080)
        band_rows = []
        for r in range(1 if quick else max(3, runs // 2)):
            whole = _dataset(b.povray, ["run", _spec(os.path.join(work, "big.toml"), big[0], big[1], 16, 1),
                                        "--out", os.path.join(work, "big-whole")])
            banded_out = os.path.join(work, "big-bands")
            banded = _dataset(b.povray, ["run", _spec(os.path.join(work, "big.toml"), big[0], big[1], 16, 1),
                                         "--out", banded_out, "--bands", "4"])
            with open(os.path.join(banded_out, "manifest.jsonl")) as f:
                record = json.loads(f.readline())
            band_rows.append({"whole_s": whole, "banded_s": banded,
                              "band_render_s": [band["render_seconds"] for band in record["bands"]]})
            log("  %dx%d raw: whole %.2f s, 4 bands %.2f s (bands %s)" % (
                big[0], big[1], whole, banded, ", ".join("%.2f" % t for t in band_rows[-1]["band_render_s"])))
            shutil.rmtree(os.path.join(work, "big-whole"), ignore_errors=True)
            shutil.rmtree(banded_out, ignore_errors=True)
        results["dataset_bands"] = {"size": list(big), "samples": 16, "bands": 4, "runs": band_rows}
    finally:
        if stop is not None:
            stop()
