# SPDX-License-Identifier: AGPL-3.0-or-later
"""Loading a render's metadata (<image>.plenoptic.json) the strict way, for every test family.

load(path) reads the file as plenoptic-project does (UTF-8 only, no lone surrogate, no key twice
in an object, no NaN or Infinity) and validates it against docs/metadata.schema.json, the
schema of docs/metadata.md. Any problem raises MetadataError (a ValueError) naming the file.
The test helpers that read metadata (tests/camera/camlib.py, tests/ground_truth/gt_common.py,
tests/golden/golden.py, tests/robustness/rtlib.py) all load it through here, so every render
of the suite is checked against the schema.

Needs Python's jsonschema (Debian package python3-jsonschema).
"""

import json
import os

SCHEMA_PATH = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "docs",
                                            "metadata.schema.json"))

_validator = None


class MetadataError(ValueError):
    pass


def validator():
    """The Draft 2020-12 validator of docs/metadata.schema.json (built once)."""
    global _validator
    if _validator is None:
        try:
            import jsonschema
        except ImportError:
            raise MetadataError("cannot validate metadata: Python's jsonschema is missing "
                                "(Debian package python3-jsonschema; tools/install-deps installs it)")
        with open(SCHEMA_PATH, encoding="utf-8") as f:
            schema = json.load(f)
        jsonschema.Draft202012Validator.check_schema(schema)
        _validator = jsonschema.Draft202012Validator(schema)
    return _validator


def _where(error):
    parts = []
    for p in error.absolute_path:
        if isinstance(p, int):
            parts.append("[%d]" % p)
        else:
            parts.append(("." if parts else "") + str(p))
    return "".join(parts) or "(top level)"


def schema_errors(doc):
    """The schema's complaints about a document, as "field: message" strings (empty: valid)."""
    errors = sorted(validator().iter_errors(doc), key=lambda e: list(map(str, e.absolute_path)))
    out = []
    for e in errors:
        # "null, or an object such that ..." (oneOf): the deepest reason of the object branch says
        # more than "is not valid under any of the given schemas".
        leaves = [l for l in _leaves(e) if not (l.validator == "type" and l.validator_value == "null")] or [e]
        deepest = max(len(l.absolute_path) for l in leaves)
        out.extend("%s: %s" % (_where(l), l.message[:200]) for l in leaves if len(l.absolute_path) == deepest)
    return out


def _leaves(error):
    if not error.context:
        return [error]
    return [leaf for c in error.context for leaf in _leaves(c)]


def validate(doc, where="metadata"):
    """Raises MetadataError when `doc` does not match docs/metadata.schema.json."""
    problems = schema_errors(doc)
    if problems:
        raise MetadataError("%s does not match docs/metadata.schema.json (%d problem(s)): %s"
                            % (where, len(problems), "; ".join(problems[:5])))


def _refuse_constant(token):
    raise MetadataError("non-finite number %s" % token)


def _unique_keys(pairs):
    doc = {}
    for key, value in pairs:
        if key in doc:
            raise MetadataError("duplicate key %r" % key)
        doc[key] = value
    return doc


def _check_strings(value):
    """A lone surrogate (\\ud800) parses in Python's json but is not Unicode text."""
    if isinstance(value, str):
        value.encode("utf-8")  # UnicodeEncodeError for a lone surrogate
    elif isinstance(value, dict):
        for k, v in value.items():
            _check_strings(k)
            _check_strings(v)
    elif isinstance(value, list):
        for v in value:
            _check_strings(v)


def parse(data, where="metadata"):
    """The document in `data` (bytes or str), read strictly; MetadataError naming `where`."""
    try:
        text = data.decode("utf-8") if isinstance(data, bytes) else data
        doc = json.loads(text, object_pairs_hook=_unique_keys, parse_constant=_refuse_constant)
        _check_strings(doc)
    except MetadataError as e:
        raise MetadataError("%s: %s" % (where, e))
    except UnicodeError as e:
        raise MetadataError("%s: not UTF-8 text (%s)" % (where, e))
    except json.JSONDecodeError as e:
        raise MetadataError("%s: not valid JSON (%s)" % (where, e))
    return doc


def load(path, check_schema=True):
    """The metadata file at `path`, read strictly and (by default) validated against the schema."""
    with open(path, "rb") as f:
        doc = parse(f.read(), path)
    if check_schema:
        validate(doc, path)
    return doc
