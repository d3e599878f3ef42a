# SPDX-License-Identifier: AGPL-3.0-or-later
"""A data set's folder: DIR/items/<id>/ per finished item (its files and item.json, the record
with checksums), DIR/manifest.jsonl (one line per finished item), DIR/failed/<id>.log.

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
    def __init__(self, root):
        self.root = os.path.abspath(root)
        self.items_dir = os.path.join(self.root, "items")
        self.failed_dir = os.path.join(self.root, "failed")
        self.manifest = os.path.join(self.root, "manifest.jsonl")

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
