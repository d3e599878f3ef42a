# SPDX-License-Identifier: AGPL-3.0-or-later
"""A data set's specification: a TOML file naming a scene, the render size, a sweep over the
scene's #declare'd identifiers, seeded random draws, per-item options and Slurm resources
(docs/datasets.md). load_spec checks every value and says which key is wrong and what is allowed;
Spec.items() lists the items, each with the values declared for its render."""

from __future__ import annotations

import hashlib
import json
import math
import os
import random
import re
import subprocess
import tempfile
import tomllib
from typing import Any, NoReturn

from ..povray import run_povray

IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
# The identifiers the per-item options are passed as (the scene reads them, docs/datasets.md).
OPTION_IDENTIFIERS = {
    "samples": "Dataset_Samples",
    "depth_map": "Dataset_Depth_Map",
    "white_image": "Dataset_White_Image",
    "sensor_seed": "Dataset_Sensor_Seed",
}
DISTRIBUTIONS = {
    "uniform": "uniform = [low, high]",
    "normal": "normal = [mean, standard deviation]",
    "loguniform": "loguniform = [low, high] (both > 0)",
    "integer": "integer = [low, high] (whole numbers, both included)",
    "choice": "choice = [value, value, ...]",
}
TOP_KEYS = {"scene", "width", "height", "povray_options", "bands", "options", "sweep", "random", "slurm"}
SLURM_KEYS = {"partition": str, "cpus_per_task": int, "mem": str, "time": str, "items_per_task": int,
              "max_parallel": int, "extra": list}


class SpecError(Exception):
    """A spec that cannot be used: the message names the file, the key and what is allowed."""


class Item:
    """One render: index (0-based, in the spec's order), id (the index and a digest of everything
    the render depends on: the values, the scene file's contents, the size and the POV-Ray
    options; so a changed spec or scene never reuses an old item's folder), declares (identifier
    -> number)."""

    def __init__(self, index: int, declares: dict[str, float], context: Any) -> None:
        self.index = index
        self.declares = declares
        text = json.dumps({"declares": declares, "context": context}, sort_keys=True)
        self.id = "%05d-%s" % (index, hashlib.sha256(text.encode()).hexdigest()[:8])

    def declarations(self) -> str:
        """The item's values as POV-Ray #declare lines, exact (the scene's Include_Header): POV-Ray
        keeps a Declare= option's value as a 32-bit float (about 7 digits), which would round
        large seeds and indices and record values other than those rendered."""
        return "".join("#declare %s = %s;\n" % (name, _number_text(value)) for name, value in self.declares.items())


def _number_text(value):
    return repr(float(value)) if not float(value).is_integer() else str(int(value))


# POV-Ray options plenoptic-dataset sets itself: switches (+X or -X followed by a value; +I and +O take
# a file name, which may start with any letter) and INI keys.
_OWN_SWITCHES = ("I", "O", "SR", "ER", "HI")
_OWN_KEYS = ("input_file_name", "output_file_name", "width", "height", "start_row", "end_row", "include_header",
             "output_file_type", "output_to_file")


def _own_option(option):
    """Why `option` is plenoptic-dataset's own, or None."""
    text = option.strip()
    if "=" in text and text[0] not in "+-":
        key = text.split("=", 1)[0].strip().lower()
        if key in _OWN_KEYS:
            return "is set by plenoptic-dataset (scene, output, size, bands, format and declarations are its own)"
        return None
    if len(text) < 2 or text[0] not in "+-":
        return None
    body = text[1:].upper()
    if body[:1] in ("W", "H") and (len(body) == 1 or body[1].isdigit()):
        return "is set by plenoptic-dataset (the spec's width and height)"
    if any(body.startswith(s) for s in _OWN_SWITCHES):
        return "is set by plenoptic-dataset (scene, output, bands and declarations are its own)"
    if body[:1] == "F" and body[:2] not in ("FN", "FE"):
        return "chooses another image format: the image is a PNG (+FN, the default +FN16) or an OpenEXR file (+FE)"
    return None


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


class Spec:
    def __init__(self, path: str, data: dict[str, Any]) -> None:
        self.path = os.path.abspath(path)
        here = os.path.dirname(self.path)

        def fail(key: str, message: str) -> NoReturn:
            raise SpecError("%s: %s: %s" % (path, key, message))

        unknown = sorted(set(data) - TOP_KEYS)
        if unknown:
            fail(unknown[0], "unknown key; a spec holds %s" % ", ".join(sorted(TOP_KEYS)))
        scene = data.get("scene")
        if not isinstance(scene, str) or not scene:
            fail("scene", "the scene file to render (a path relative to the spec) is required")
        self.scene = os.path.normpath(os.path.join(here, scene))
        if not os.path.isfile(self.scene):
            fail("scene", "%s does not exist" % self.scene)
        with open(self.scene, "rb") as f:
            scene_digest = hashlib.sha256(f.read()).hexdigest()
        for key in ("width", "height"):
            value = data.get(key)
            if not (isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= 100000):
                fail(key, "a whole number of pixels from 1 to 100000 is required, got %r" % (value,))
        self.width, self.height = data["width"], data["height"]
        options = data.get("povray_options", [])
        if not (isinstance(options, list) and all(isinstance(o, str) and o for o in options)):
            fail("povray_options", "a list of POV-Ray options as strings, e.g. [\"+A0.1\"], got %r" % (options,))
        for o in options:
            why = _own_option(o)
            if why:
                fail("povray_options", "%r %s" % (o, why))
        self.povray_options = list(options)
        self.context = {"scene": scene_digest, "width": self.width, "height": self.height, "options": self.povray_options}
        bands = data.get("bands", 1)
        if not (isinstance(bands, int) and not isinstance(bands, bool) and 1 <= bands <= self.height):
            fail("bands", "a whole number of row bands from 1 to the height (%d), got %r" % (self.height, bands))
        self.bands = bands

        self.options = {}
        raw_options = data.get("options", {})
        if not isinstance(raw_options, dict):
            fail("options", "a table [options] of samples, depth_map, white_image, sensor_seed")
        for key, value in raw_options.items():
            where = "options.%s" % key
            if key not in OPTION_IDENTIFIERS:
                fail(where, "unknown option; [options] takes %s" % ", ".join(OPTION_IDENTIFIERS))
            if key == "samples" and not (isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= 1000000):
                fail(where, "a whole number of samples per pixel from 1 to 1000000, got %r" % (value,))
            if key in ("depth_map", "white_image") and not isinstance(value, bool):
                fail(where, "true or false, got %r" % (value,))
            if key == "sensor_seed" and not (isinstance(value, int) and not isinstance(value, bool) and 0 <= value < 2 ** 31):
                fail(where, "a whole number from 0 to 2^31 - 1 (each item adds its index), got %r" % (value,))
            self.options[key] = value

        self.sweep = {}
        sweep = data.get("sweep", {})
        if not isinstance(sweep, dict):
            fail("sweep", "a table [sweep] of identifier = [values]")
        for name, values in sweep.items():
            where = "sweep.%s" % name
            self._check_identifier(fail, where, name)
            if not (isinstance(values, list) and values and all(_is_number(v) for v in values)):
                fail(where, "a non-empty list of finite numbers (declared as POV-Ray floats), got %r" % (values,))
            self.sweep[name] = [float(v) if isinstance(v, float) else v for v in values]

        self.count, self.seed, self.draws = 1, 0, {}
        rand = data.get("random", None)
        if rand is not None:
            if not isinstance(rand, dict):
                fail("random", "a table [random] with count, seed and identifier = { distribution = [...] }")
            count = rand.get("count")
            if not (isinstance(count, int) and not isinstance(count, bool) and 1 <= count <= 10000000):
                fail("random.count", "a whole number of draws from 1 to 10000000 is required, got %r" % (count,))
            seed = rand.get("seed", 0)
            if not (isinstance(seed, int) and not isinstance(seed, bool)):
                fail("random.seed", "a whole number, got %r" % (seed,))
            self.count, self.seed = count, seed
            for name, law in rand.items():
                if name in ("count", "seed"):
                    continue
                where = "random.%s" % name
                self._check_identifier(fail, where, name)
                if name in self.sweep:
                    fail(where, "is swept in [sweep] too; an identifier is either swept or drawn")
                if not (isinstance(law, dict) and len(law) == 1 and next(iter(law)) in DISTRIBUTIONS):
                    fail(where, "one distribution: %s" % "; ".join(DISTRIBUTIONS.values()))
                kind, params = next(iter(law.items()))
                ok = isinstance(params, list) and all(_is_number(p) for p in params)
                if kind in ("uniform", "normal", "loguniform", "integer"):
                    ok = ok and len(params) == 2
                if kind == "uniform" or kind == "integer":
                    ok = ok and params[0] <= params[1]
                if kind == "integer":
                    ok = ok and all(float(p).is_integer() for p in params)
                if kind == "normal":
                    ok = ok and params[1] >= 0
                if kind == "loguniform":
                    ok = ok and 0 < params[0] <= params[1]
                if kind == "choice":
                    ok = ok and len(params) >= 1
                if not ok:
                    fail(where, "%s, got %r" % (DISTRIBUTIONS[kind], params))
                self.draws[name] = (kind, params)

        self.slurm = {"items_per_task": 1}
        slurm = data.get("slurm", {})
        if not isinstance(slurm, dict):
            fail("slurm", "a table [slurm] of %s" % ", ".join(SLURM_KEYS))
        for key, value in slurm.items():
            where = "slurm.%s" % key
            if key not in SLURM_KEYS:
                fail(where, "unknown key; [slurm] takes %s" % ", ".join(SLURM_KEYS))
            kind = SLURM_KEYS[key]
            if not isinstance(value, kind) or isinstance(value, bool) or (kind is int and value < 1):
                fail(where, "a %s, got %r" % ("positive whole number" if kind is int else
                                               "list of sbatch options" if kind is list else "string", value))
            self.slurm[key] = value

        total = self.item_count()
        if total > 10000000:
            fail("sweep", "%d items (sweep combinations x random.count); at most 10000000" % total)

    @staticmethod
    def _check_identifier(fail, where, name):
        if not IDENTIFIER.match(name):
            fail(where, "a POV-Ray identifier (a letter or _, then letters, digits or _) is required")
        if name.startswith("Dataset_"):
            fail(where, "identifiers starting with Dataset_ are plenoptic-dataset's own ([options])")

    def check_reserved_words(self, povray: str) -> None:
        """Refuses (SpecError) a swept or drawn identifier that is one of the renderer's reserved
        words (x, pi, clock, sphere, plenoptic, ...), which every item's render would refuse. Asks
        the renderer itself: it parses `#declare NAME = 0;` for each of them (no image), and
        names the line of the first it refuses as a reserved word."""
        names = list(self.sweep) + list(self.draws)
        if not names:
            return
        with tempfile.TemporaryDirectory(prefix="plenoptic-dataset-") as folder:
            scene = os.path.join(folder, "identifiers.pov")
            with open(scene, "w") as f:
                f.write("".join("#declare %s = 0;\n" % name for name in names))
            try:
                command = [povray, "+I" + os.path.basename(scene), "+W1", "+H1", "-F", "-D", "-P"]
                run = run_povray(command, cwd=folder, timeout=120)
                if run.timed_out:
                    raise subprocess.TimeoutExpired(command, 120)
            except (OSError, subprocess.TimeoutExpired) as e:
                raise SpecError("%s: cannot check the identifiers with %s: %s" % (self.path, povray, e)) from None
        if run.returncode == 0:
            return
        # POV-Ray wraps its messages at 80 columns.
        refused = re.search(r"line (\d+): Parse Error: Expected 'undeclared identifier'", " ".join(run.output.split()))
        if refused and 1 <= int(refused.group(1)) <= len(names):
            name = names[int(refused.group(1)) - 1]
            raise SpecError("%s: %s.%s: %r is a reserved word of POV-Ray (the renderer refuses to #declare it); "
                            "choose another identifier for the scene" % (self.path, "sweep" if name in self.sweep
                                                                          else "random", name, name))
        tail = " | ".join(line.strip() for line in run.output.strip().splitlines()[-3:])
        raise SpecError("%s: cannot check the identifiers: %s exits %s on a scene that only declares them: %s"
                        % (self.path, povray, run.returncode, tail))

    def item_count(self) -> int:
        combos = 1
        for values in self.sweep.values():
            combos *= len(values)
        return combos * self.count

    def _draw(self, k, name):
        kind, params = self.draws[name]
        rng = random.Random("plenoptic-dataset:%d:%d:%s" % (self.seed, k, name))
        if kind == "uniform":
            return rng.uniform(params[0], params[1])
        if kind == "normal":
            return rng.gauss(params[0], params[1])
        if kind == "loguniform":
            return math.exp(rng.uniform(math.log(params[0]), math.log(params[1])))
        if kind == "integer":
            return rng.randint(int(params[0]), int(params[1]))
        return params[rng.randrange(len(params))]

    def item(self, index: int) -> Item:
        """Item `index` (0-based): the sweep's combination index // count (the last swept
        identifier varying fastest) and draw index % count."""
        if not 0 <= index < self.item_count():
            raise IndexError("item %d of %d" % (index, self.item_count()))
        combo, k = divmod(index, self.count)
        declares = {}
        sizes = [len(v) for v in self.sweep.values()]
        picks = []
        for size in reversed(sizes):
            combo, pick = divmod(combo, size)
            picks.append(pick)
        for (name, values), pick in zip(self.sweep.items(), reversed(picks)):
            declares[name] = values[pick]
        for name in self.draws:
            declares[name] = self._draw(k, name)
        for key, value in self.options.items():
            if key == "sensor_seed":
                value = value + index
            declares[OPTION_IDENTIFIERS[key]] = int(value) if isinstance(value, bool) else value
        declares["Dataset_Item"] = index
        return Item(index, declares, self.context)

    def items(self) -> list[Item]:
        if getattr(self, "_items", None) is None:
            self._items = [self.item(i) for i in range(self.item_count())]
        return self._items


def load_spec(path: str) -> Spec:
    """The Spec in the TOML file at `path`; SpecError naming the file, the key and what is allowed."""
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except OSError as e:
        raise SpecError("%s: cannot read: %s" % (path, e.strerror or e)) from None
    except tomllib.TOMLDecodeError as e:
        raise SpecError("%s: not valid TOML: %s" % (path, e)) from None
    return Spec(path, data)
