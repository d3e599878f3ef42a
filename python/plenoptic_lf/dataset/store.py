# SPDX-License-Identifier: AGPL-3.0-or-later
"""A data set's folder: DIR/dataset.json (the spec whose data set the folder holds),
DIR/items/<id>/ per finished item (its files and item.json, the record with checksums),
DIR/manifest.jsonl (one line per finished item), DIR/failed/<id>.log.

An item is finished when its folder exists under its final name and every file its record lists
has the recorded size and SHA-256: items are rendered into DIR/items/.partial-<id>-<random>/ and
renamed into place only when complete, so a half-written item never counts."""

import hashlib
import json
import os
import shutil
import tempfile
import time

RECORD = "item.json"
SPEC_RECORD = "dataset.json"


class OtherDataset(Exception):
    """The folder holds another spec's data set (the message says whose, and how to replace it)."""


def _write_atomically(path, text):
    fd, tmp = tempfile.mkstemp(prefix=".%s-" % os.path.basename(path), dir=os.path.dirname(path))
    with os.fdopen(fd, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def sha256_of(path):
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def replace_folder(new, final):
    """Renames the folder `new` to `final`. An earlier `final` (unverified, or another finisher's)
    is first renamed aside and removed only after the new one is in place, so that at every moment
    one complete folder or none stands under the final name."""
    old = None
    if os.path.exists(final):
        old = tempfile.mkdtemp(prefix=".partial-old-", dir=os.path.dirname(final))
        os.rmdir(old)
        try:
            os.rename(final, old)
        except FileNotFoundError:  # another finisher moved it first
            old = None
    try:
        os.rename(new, final)
    except OSError:
        if old is not None and not os.path.exists(final):
            os.rename(old, final)
            old = None
        raise
    finally:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)


class Store:
    def __init__(self, root: str) -> None:
        self.root = os.path.abspath(root)
        self.items_dir = os.path.join(self.root, "items")
        self.failed_dir = os.path.join(self.root, "failed")
        self.manifest = os.path.join(self.root, "manifest.jsonl")

    def spec_record(self):
        """DIR/dataset.json as a dict; None when there is none, {} when it cannot be read."""
        path = os.path.join(self.root, SPEC_RECORD)
        if not os.path.exists(path):
            return None
        try:
            with open(path) as f:
                record = json.load(f)
        except (OSError, ValueError):
            return {}
        return record if isinstance(record, dict) else {}

    def _present(self):
        """{id: whether finished} of the items the folder holds: items/<id>/ (finished when its
        item.json is there), bands/<id>/ and failed/<id>.log (not finished)."""
        present = {}
        for folder, suffix in ((self.items_dir, ""), (os.path.join(self.root, "bands"), ""), (self.failed_dir, ".log")):
            try:
                names = os.listdir(folder)
            except OSError:
                continue
            for name in names:
                if name.startswith(".") or not name.endswith(suffix):
                    continue
                item_id = name[:len(name) - len(suffix)] if suffix else name
                finished = folder == self.items_dir and os.path.exists(os.path.join(folder, name, RECORD))
                present[item_id] = present.get(item_id, False) or finished
        return present

    def claim(self, spec, items, replace=False, jobs_running=None):
        """Makes the folder the data set of `spec` (whose items are `items`), recording it in
        DIR/dataset.json. The same data set (the same item ids in the same order: the spec file may
        have been moved, or its [slurm] table, bands or comments edited) is resumed. Another spec's
        data set (recorded, or, in a folder without a record, items the spec does not have) raises
        OtherDataset, unless `replace`: then the items `spec` does not have (finished or not, their
        bands and failed logs), the manifest and the Slurm folder are deleted first, and the items
        both specs have (the same render inputs, so the same pictures) are kept. `jobs_running()`
        lists the folder's Slurm jobs still queued or running: replacing is refused while there are.
        Returns None when the folder already held this data set (or nothing), else the number of
        finished items deleted."""
        ids = [item.id for item in items]
        digest = hashlib.sha256("\n".join(ids).encode()).hexdigest()
        with open(spec.path, "rb") as f:
            text = f.read().decode("utf-8", errors="replace")
        record = {"format": "plenoptic-dataset", "version": 1, "spec": spec.path,
                  "spec_sha256": hashlib.sha256(text.encode()).hexdigest(), "scene": spec.scene,
                  "items": len(ids), "items_sha256": digest, "spec_text": text}
        recorded = self.spec_record()
        wanted = set(ids)
        present = self._present()
        foreign = {i: finished for i, finished in present.items() if i not in wanted}
        if recorded is not None and recorded.get("items_sha256") == digest:
            same = True
        elif recorded is None:  # a new folder, or one written before data sets were recorded
            same = not foreign
        else:
            same = False
        if not same:
            where = os.path.join(self.root, SPEC_RECORD)
            if recorded:
                whose = "the data set of %s (%s items, recorded in %s)" % (recorded.get("spec", "another spec"),
                                                                         recorded.get("items", "?"), where)
            elif recorded is None:
                whose = "items of another spec (no %s: written by an older plenoptic-dataset)" % SPEC_RECORD
            else:
                whose = "a data set whose record %s cannot be read" % where
            lost = sum(1 for finished in foreign.values() if finished)
            if not replace:
                name = os.path.basename(spec.path)
                raise OtherDataset(
                    "%s holds %s, not that of %s (%d items, %d of them in the folder; an item changes with its "
                    "values, the scene file, the size and the POV-Ray options). Render into another folder, or add "
                    "--replace to make the folder %s's data set (deletes the %d finished items %s does not have, "
                    "keeps those it has)" % (self.root, whose, spec.path, len(ids),
                                             sum(1 for i in present if i in wanted), name, lost, name))
            running = jobs_running() if jobs_running is not None else []
            if running:
                raise OtherDataset("job %s of the data set in %s is still queued or running on Slurm: wait for it, "
                                   "or cancel it with scancel, then replace the data set"
                                   % (" ".join(map(str, running)), self.root))
            for item_id in foreign:
                shutil.rmtree(self.item_dir(item_id), ignore_errors=True)
                shutil.rmtree(os.path.join(self.root, "bands", item_id), ignore_errors=True)
                try:
                    os.remove(os.path.join(self.failed_dir, item_id + ".log"))
                except FileNotFoundError:
                    pass
            shutil.rmtree(os.path.join(self.root, "slurm"), ignore_errors=True)
            try:
                os.remove(self.manifest)
            except FileNotFoundError:
                pass
            self.clear_partials()
        if recorded != dict(record, recorded_at=(recorded or {}).get("recorded_at")) or not same:
            record["recorded_at"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
            os.makedirs(self.root, exist_ok=True)
            _write_atomically(os.path.join(self.root, SPEC_RECORD), json.dumps(record, indent=1, sort_keys=True) + "\n")
        return None if same else sum(1 for finished in foreign.values() if finished)

    def create(self):
        os.makedirs(self.items_dir, exist_ok=True)
        os.makedirs(self.failed_dir, exist_ok=True)

    def item_dir(self, item_id):
        return os.path.join(self.items_dir, item_id)

    def partial_dir(self, item_id, tag=""):
        """A new, empty folder to render item `item_id` (part `tag`) into."""
        return tempfile.mkdtemp(prefix=".partial-%s%s-" % (item_id, tag), dir=self.items_dir)

    def record(self, item_id):
        """The item's record (dict) when it is finished and verified, else None."""
        folder = self.item_dir(item_id)
        try:
            with open(os.path.join(folder, RECORD)) as f:
                record = json.load(f)
        except (OSError, ValueError):
            return None
        if record.get("id") != item_id or not isinstance(record.get("files"), dict):
            return None
        for name, entry in record["files"].items():
            path = os.path.join(folder, name)
            try:
                if os.path.getsize(path) != entry["bytes"] or sha256_of(path) != entry["sha256"]:
                    return None
            except (OSError, KeyError, TypeError):
                return None
        return record

    def finish(self, partial, item_id, record):
        """Lists the files of `partial` with their checksums in the record, writes it, and renames
        the folder into place (an earlier, unverified folder of the item is removed first).
        Returns the record."""
        files = {}
        for name in sorted(os.listdir(partial)):
            path = os.path.join(partial, name)
            if os.path.isfile(path) and name != RECORD:
                files[name] = {"bytes": os.path.getsize(path), "sha256": sha256_of(path)}
        record = dict(record, id=item_id, files=files,
                      finished_at=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
        if isinstance(record.get("command"), list):  # name the folder the files end up in
            record["command"] = [arg.replace(partial, self.item_dir(item_id)) for arg in record["command"]]
        with open(os.path.join(partial, RECORD), "w") as f:
            json.dump(record, f, indent=1, sort_keys=True)
            f.flush()
            os.fsync(f.fileno())
        replace_folder(partial, self.item_dir(item_id))
        failed = os.path.join(self.failed_dir, item_id + ".log")
        if os.path.exists(failed):
            os.remove(failed)
        return record

    def fail(self, partial, item_id, log_text):
        """Keeps the item's log as DIR/failed/<id>.log and removes its partial folder."""
        path = os.path.join(self.failed_dir, item_id + ".log")
        with open(path, "w") as f:
            f.write(log_text)
        if partial and os.path.exists(partial):
            shutil.rmtree(partial, ignore_errors=True)
        return path

    def clear_partials(self, item_id=None):
        """Removes partial folders left by interrupted renders (of one item, or all)."""
        if not os.path.isdir(self.items_dir):
            return
        for name in os.listdir(self.items_dir):
            if name.startswith(".partial-") and (item_id is None or name.startswith(".partial-%s" % item_id)):
                shutil.rmtree(os.path.join(self.items_dir, name), ignore_errors=True)

    def finished(self, items):
        """{id: record} of the given items that are finished and verified."""
        done = {}
        for item in items:
            record = self.record(item.id)
            if record is not None:
                done[item.id] = record
        return done

    def write_manifest(self, records):
        """DIR/manifest.jsonl: one line per record, in item order, replaced atomically."""
        fd, tmp = tempfile.mkstemp(prefix=".manifest-", dir=self.root)
        with os.fdopen(fd, "w") as f:
            for record in sorted(records, key=lambda r: r["index"]):
                f.write(json.dumps(record, sort_keys=True) + "\n")
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.manifest)

    def append_manifest(self, record):
        with open(self.manifest, "a") as f:
            f.write(json.dumps(record, sort_keys=True) + "\n")
            f.flush()
            os.fsync(f.fileno())
