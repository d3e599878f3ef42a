# SPDX-License-Identifier: AGPL-3.0-or-later
"""Renders items into a data set's folder: one item (whole, or in row bands merged by rows),
and the local executor's loop over every item not yet finished, with progress."""

import json
import os
import shutil
import sys
import time

from .bands import BandError, band_rows, check_mergeable, merge
from .render import image_extension, render
from .store import replace_folder


class ItemFailed(Exception):
    """An item that could not be rendered: message, and the path of its kept log."""

    def __init__(self, message, log_path):
        super().__init__(message)
        self.log_path = log_path


def base_record(spec, item):
    return {"index": item.index, "parameters": item.declares, "scene": os.path.basename(spec.scene),
            "width": spec.width, "height": spec.height, "image": item.id + image_extension(spec)}


def _tail(text, lines=8):
    return "\n".join("    " + line for line in text.strip().splitlines()[-lines:])


def band_dir(store, item_id, k):
    return os.path.join(store.root, "bands", item_id, "band-%d" % k)


def band_record(folder):
    """A finished band's record (band.json), or None."""
    try:
        with open(os.path.join(folder, "band.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def render_band(store, spec, item, povray, k, rows):
    """Renders band k (rows (first, last)) of the item and moves it to DIR/bands/<id>/band-<k>/
    when complete; ItemFailed (its log kept) otherwise."""
    partial = store.partial_dir(item.id, "-band%d" % k)
    try:
        result = render(povray, spec, item, partial, rows)
        if not result.ok:
            path = store.fail(partial, item.id, result.log)
            raise ItemFailed("item %s, band %d (rows %d-%d) failed (POV-Ray exit %s):\n%s"
                             % (item.id, k, rows[0], rows[1], result.status, _tail(result.log)), path)
        if k == 0:
            try:
                check_mergeable(partial, item.id)
            except BandError as e:
                path = store.fail(partial, item.id, result.log + "\nplenoptic-dataset: %s\n" % e)
                raise ItemFailed("item %s: %s" % (item.id, e), path) from None
        record = dict(result.record(), rows=list(rows))
        with open(os.path.join(partial, "band.json"), "w") as f:
            json.dump(record, f, indent=1, sort_keys=True)
        final = band_dir(store, item.id, k)
        os.makedirs(os.path.dirname(final), exist_ok=True)
        replace_folder(partial, final)
        return record
    finally:
        if os.path.exists(partial):
            shutil.rmtree(partial, ignore_errors=True)


def merge_item(store, spec, item, bands):
    """Merges the item's finished bands (all of them must be there) into its folder; its record.
    Whatever happens, no partial folder is left behind."""
    rows = band_rows(spec.height, bands)
    folders = [band_dir(store, item.id, k) for k in range(len(rows))]
    records = [band_record(folder) for folder in folders]
    logs = ""
    for folder in folders:
        try:
            with open(os.path.join(folder, "render.log")) as f:
                logs += f.read()
        except OSError:
            pass
    partial = store.partial_dir(item.id)
    try:
        try:
            if any(r is None or r.get("rows") != list(band) for r, band in zip(records, rows)):
                raise BandError("not every band is finished (or they were rendered with another band count)")
            merge(folders, rows, item.id, image_extension(spec), partial)
        except (BandError, OSError) as e:
            path = store.fail(partial, item.id, logs + "\nplenoptic-dataset: merging the bands failed: %s\n" % e)
            raise ItemFailed("item %s: merging its %d bands failed: %s" % (item.id, len(rows), e), path) from None
        with open(os.path.join(partial, "render.log"), "w") as f:
            f.write(logs)
        record = base_record(spec, item)
        record["host"] = records[0]["host"]
        record["render_seconds"] = round(sum(r["render_seconds"] for r in records), 3)
        record["cpu_seconds"] = round(sum(r["cpu_seconds"] for r in records), 3)
        record["bands"] = [{"rows": r["rows"], "render_seconds": r["render_seconds"], "host": r["host"],
                            "command": r["command"]} for r in records]
        record = store.finish(partial, item.id, record)
    finally:
        if os.path.exists(partial):
            shutil.rmtree(partial, ignore_errors=True)
    shutil.rmtree(os.path.join(store.root, "bands", item.id), ignore_errors=True)
    try:
        os.rmdir(os.path.join(store.root, "bands"))  # when no other item's bands wait there
    except OSError:
        pass
    return record


def run_item(store, spec, item, povray, bands=1):
    """Renders one item (in `bands` row bands when more than 1, each kept once finished) and
    finishes it; its record, or ItemFailed. KeyboardInterrupt leaves no partial folder behind."""
    if bands <= 1:
        folder = store.partial_dir(item.id)
        try:
            result = render(povray, spec, item, folder)
            if not result.ok:
                path = store.fail(folder, item.id, result.log)
                raise ItemFailed("item %s failed (POV-Ray exit %s):\n%s" % (item.id, result.status, _tail(result.log)), path)
            record = base_record(spec, item)
            record.update(result.record())
            return store.finish(folder, item.id, record)
        finally:
            if os.path.exists(folder):
                shutil.rmtree(folder, ignore_errors=True)
    for k, rows in enumerate(band_rows(spec.height, bands)):
        existing = band_record(band_dir(store, item.id, k))
        if existing is None or existing.get("rows") != list(rows):
            render_band(store, spec, item, povray, k, rows)
    return merge_item(store, spec, item, bands)


class ItemProgress:
    """'N/M items (F failed), R items/min, ETA T' on stderr: after every item, and on a terminal
    rewritten in place."""

    def __init__(self, total, already, enabled=True, prefix="plenoptic-dataset"):
        self.total, self.already, self.enabled, self.prefix = total, already, enabled, prefix
        self.done, self.failed = 0, 0
        self.start = time.monotonic()
        self.tty = enabled and sys.stderr.isatty()

    def line(self):
        elapsed = time.monotonic() - self.start
        finished = self.already + self.done
        text = "%s: %d/%d items" % (self.prefix, finished, self.total)
        if self.failed:
            text += " (%d failed)" % self.failed
        if self.done and elapsed > 0:
            rate = self.done / elapsed
            left = self.total - finished - self.failed
            text += ", %.3g items/min, ETA %s" % (rate * 60, _duration(left / rate) if left > 0 else "0 s")
        return text

    def show(self):
        if not self.enabled:
            return
        if self.tty:
            sys.stderr.write("\r\033[K" + self.line())
        else:
            sys.stderr.write(self.line() + "\n")
        sys.stderr.flush()

    def message(self, text):
        if self.enabled:
            sys.stderr.write(("\r\033[K" if self.tty else "") + text + "\n")
            self.show()

    def close(self):
        if self.tty:
            sys.stderr.write("\n")


def _duration(seconds):
    if seconds < 90:
        return "%.0f s" % seconds
    if seconds < 5400:
        return "%.0f min" % (seconds / 60)
    return "%.1f h" % (seconds / 3600)


def run_local(store, spec, povray, bands=1, quiet=False):
    """Renders every item not finished and verified; returns (finished count, [ItemFailed])."""
    items = spec.items()
    store.create()
    store.clear_partials()
    done = store.finished(items)
    store.write_manifest(done.values())
    progress = ItemProgress(len(items), len(done), enabled=not quiet)
    if done and not quiet:
        progress.message("%s: %d of %d items already finished and verified; rendering the other %d"
                         % (progress.prefix, len(done), len(items), len(items) - len(done)))
    progress.show()
    failures = []
    try:
        for item in items:
            if item.id in done:
                continue
            try:
                record = run_item(store, spec, item, povray, bands)
            except ItemFailed as failure:
                failures.append(failure)
                progress.failed += 1
                progress.message("%s: %s\n    (log: %s)" % (progress.prefix, failure, failure.log_path))
                continue
            store.append_manifest(record)
            done[item.id] = record
            progress.done += 1
            progress.show()
    finally:
        progress.close()
        # Appended as items finish (nothing is lost on a crash); in item order once the run ends.
        store.write_manifest(done.values())
    return len(done), failures
