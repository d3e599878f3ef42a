# SPDX-License-Identifier: AGPL-3.0-or-later
"""The report of section dataset (BENCHMARKS.md, "Data sets")."""
import statistics


def dataset_report(L, results):
    d = results["dataset"]
    L.append("## Data sets (`--only dataset`)\n")
    L.append("`plenoptic-dataset` (docs/datasets.md) on `scenes/dataset_demo.pov`: %d items of %dx%d, %d samples, depth"
             " map on, rendered (1) by the same POV-Ray commands run bare one after the other, (2) by the local"
             " executor, (3) by the Slurm executor on `tools/slurm-local`'s one-node cluster (each array task"
             " given every core, so that tasks run one after the other as the others do; the cluster starts the"
             " next task about a second after one ends, `tools/slurm-local`'s scheduler settings). Medians of %d"
             " rounds; whole-command clock time, divided by the items.\n"
             % (d["items"], d["size"][0], d["size"][1], d["samples"], len(d["runs"])))
    L.append("| runner | per item, s | overhead per item against bare POV-Ray, s |\n|---|---|---|")
    bare = d["per_item_s"]["bare_s"]
    for key, label in (("bare_s", "bare POV-Ray runs"), ("local_s", "plenoptic-dataset, local"),
                       ("slurm_s", "plenoptic-dataset, Slurm (one node), one item a task"),
                       ("slurm6_s", "plenoptic-dataset, Slurm (one node), 6 items a task (`items_per_task = 6`)")):
        if key in d["per_item_s"]:
            t = d["per_item_s"][key]
            L.append("| %s | %.3f | %+.3f |" % (label, t, t - bare))
    b = results.get("dataset_bands")
    if b:
        whole = statistics.median(r["whole_s"] for r in b["runs"])
        banded = statistics.median(r["banded_s"] for r in b["runs"])
        longest = statistics.median(max(r["band_render_s"]) for r in b["runs"])
        L.append("\nOne %dx%d raw at %d samples, whole and in %d row bands (`--bands %d`, local executor: the bands"
                 " one after the other, then the merge): medians of %d rounds.\n"
                 % (b["size"][0], b["size"][1], b["samples"], b["bands"], b["bands"], len(b["runs"])))
        L.append("| | clock, s |\n|---|---|")
        L.append("| one render | %.2f |" % whole)
        L.append("| %d bands in a row, merged | %.2f (%.2fx) |" % (b["bands"], banded, banded / whole))
        L.append("| the longest band alone (its time on %d nodes at once) | %.2f (%.2fx) |" % (b["bands"], longest, longest / whole))
        L.append("\nEach band still pays POV-Ray's start-up and parsing and the camera's set-up, and bands of"
                 " unequal content take unequal times, so N bands on N nodes finish in more than 1/N of the time.")
    f = results.get("fullsize")
    if f and "per_item_s" in d:
        one = f["median_s"] * 16
        overhead = max(d["per_item_s"].get("slurm_s", d["per_item_s"]["local_s"]) - bare, 0.0)
        L.append("\n**On paper: 10,000 Lytro-class items.** The full-size section's %.1f Mpx raw traces in %.1f s"
                 " at one sample on this 2-core machine; at 16 samples at most 16 times that (the trace grows with"
                 " the samples, start-up and set-up do not), %.0f s (%.1f min) an item, so 10,000 items take at"
                 " most %.0f hours here. On N nodes of c cores (POV-Ray's threads scale about"
                 " linearly, section threads) that is %.0f / (N c / 2) hours: %.0f h on 10 nodes of 32 cores,"
                 " %.1f h on 100. The executor's own overhead, %.2f s an item measured above, adds %.1f node-hours"
                 " in all; each array task also waits for Slurm's scheduling (seconds) and reads the scene and"
                 " writes some 200-400 MB of raw and ground truth per item (2-4 TB for the set), which a shared"
                 " file system must absorb at 10,000 items per run."
                 % (f["size"][0] * f["size"][1] / 1e6, f["median_s"], one, one / 60, 10000 * one / 3600,
                    10000 * one / 3600, 10000 * one / 3600 / (10 * 32 / 2), 10000 * one / 3600 / (100 * 32 / 2),
                    overhead, 10000 * overhead / 3600))
    L.append("")
