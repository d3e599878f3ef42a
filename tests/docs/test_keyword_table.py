# SPDX-License-Identifier: AGPL-3.0-or-later
"""The camera's keyword table against the specification's keyword tables.

The parser reads every block of `camera { plenoptic ... }` through one table
(source/povray_glue/plenoptic_keywords.cpp: word, block, value kind, check, store, default,
one-line doc); plenoptic-keyword-table, built from the same table, lists it. The user's
definition of the keywords is the tables of docs/specification.md, section 1, "Keywords", in the
format its HTML comment there describes (one Markdown table per block, the first cell the keyword
in backticks, the second its block). This test reads both and fails with the rows that differ:

1. a keyword the parser takes in a block has no row in that block's table (parsed but
   undocumented), or a documented keyword is not the parser's in that block, or a keyword has
   two rows in one block;
2. the value column says a different kind of value than the parser reads (flag, block, on/off,
   word, string, a 2-, 3- or 6-vector, a list, one number, N or MIN, MAX), or a block's or on/off
   keyword's value names other keywords or modifiers than the block the parser reads after it;
3. the default column says another default than the table (compared after dropping backticks
   and parenthesised remarks).

The Placement table (POV-Ray's own camera modifiers, read by POV-Ray's camera parser) is not part
of the comparison. Reads docs/specification.md from --source-dir and the program from --build-dir.
"""
import os
import re
from typing import Dict, List, NamedTuple

import pytest

from plenoptic_testing.keywords import keyword_table

COLUMNS = ["keyword", "block", "value", "unit", "default", "allowed", "meaning"]
# The heading of the table of POV-Ray's own placement modifiers (not the camera's table).
PLACEMENT = "Placement"


class SpecRow(NamedTuple):
    line: int
    heading: str
    cells: Dict[str, str]


def split_row(line: str) -> List[str]:
    """The cells of a Markdown table row (a `\\|` inside a cell is text)."""
    body = line.strip()
    body = body[1:] if body.startswith("|") else body
    body = body[:-1] if body.endswith("|") and not body.endswith("\\|") else body
    return [cell.strip() for cell in re.split(r"(?<!\\)\|", body)]


def spec_rows(path: str) -> List[SpecRow]:
    """The rows of the keyword tables: between the heading "### Keywords" and the next heading of
    level 2 or 3, each table under its "####" heading; the Placement table left out."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    assert "### Keywords" in lines, "%s has no heading '### Keywords'" % path
    rows: List[SpecRow] = []
    heading, header = "", None
    for number, line in enumerate(lines[lines.index("### Keywords") + 1:], lines.index("### Keywords") + 2):
        if re.match(r"#{2,3} ", line):
            break
        if line.startswith("#### "):
            heading, header = line[5:].strip(), None
            continue
        if not line.startswith("|"):
            header = None
            continue
        cells = split_row(line)
        if header is None:
            header = cells
            assert header == COLUMNS, "%s:%d: a keyword table with the columns %s, not %s" % (
                path, number, COLUMNS, header)
            continue
        if all(re.fullmatch(r":?-+:?", cell) for cell in cells):
            continue
        assert len(cells) == len(COLUMNS), "%s:%d: %d cells, not %d" % (path, number, len(cells), len(COLUMNS))
        if heading != PLACEMENT:
            rows.append(SpecRow(number, heading, dict(zip(COLUMNS, cells))))
    return rows


def word_of(cell: str) -> str:
    """The keyword or block of a cell that is one name in backticks, else ""."""
    m = re.fullmatch(r"`([a-z_0-9]+)`", cell)
    return m.group(1) if m else ""


def documented_kind(cell: str) -> str:
    """The kind of value a value cell describes, in the table's terms."""
    text = cell.replace("`", "").strip()
    for kind in ("flag", "block", "on/off"):
        if text.startswith(kind):
            return kind
    if text in ("word", "string"):
        return text
    vector = re.search(r"<([^<>]*)>", text)
    if vector:
        items = [item.strip() for item in vector.group(1).split(",")]
        return "list" if "..." in items else "vector%d" % len(items)
    if re.fullmatch(r"\w+, or \w+, \w+", text):
        return "numbers"
    if re.fullmatch(r"\w+", text):
        return "number"
    return "? (%s)" % text


# The table's value kinds and the kind of the specification's value cell each must have.
KINDS = {"flag": "flag", "number": "number", "vector2": "vector2", "vector3": "vector3", "vector6": "vector6",
         "on/off": "on/off",
         "word": "word", "string": "string", "block": "block", "samples": "numbers", "f_numbers": "list",
         "float_list": "list", "number_pair": "numbers"}


def named_keywords(cell: str) -> List[str]:
    """The keywords a value cell names in backticks ("block `{ }` of `surface` and `stop` rows")."""
    return [name for name in re.findall(r"`([^`]*)`", cell) if re.fullmatch(r"[a-z_0-9]+", name)]


def normalised_default(text: str) -> str:
    """A default as compared: no backticks, no parenthesised remark, single spaces."""
    text = text.replace("`", "")
    while re.search(r"\([^()]*\)", text):
        text = re.sub(r"\s*\([^()]*\)", "", text)
    text = re.sub(r"\s+", " ", text).strip()
    return re.sub(r" ([,;:.])", r"\1", text)


@pytest.fixture(scope="module")
def table(args):
    rows = keyword_table(args.build_dir)
    print("the parser's keyword table: %d rows" % len(rows))
    return rows


@pytest.fixture(scope="module")
def spec(args):
    path = os.path.join(args.source_dir, "docs", "specification.md")
    rows = spec_rows(path)
    print("%s: %d keyword rows" % (path, len(rows)))
    return rows


def where(row: SpecRow) -> str:
    return "docs/specification.md:%d (%s)" % (row.line, row.heading)


def test_specification_rows_name_a_keyword_and_a_block(spec):
    assert spec, "no keyword rows under '### Keywords' in docs/specification.md"
    bad = ["%s: %s | %s" % (where(r), r.cells["keyword"], r.cells["block"]) for r in spec
           if not word_of(r.cells["keyword"]) or not word_of(r.cells["block"])]
    assert not bad, "rows whose first two cells are not a keyword and a block in backticks:\n" + "\n".join(bad)


def test_every_parsed_keyword_is_documented(table, spec):
    documented = {(word_of(r.cells["keyword"]), word_of(r.cells["block"])) for r in spec}
    missing = ["`%s` in block `%s` (%s)" % (k.word, k.block, k.doc) for k in table if (k.word, k.block) not in documented]
    assert not missing, ("keywords the parser reads that the keyword tables of docs/specification.md do not "
                         "have:\n" + "\n".join(missing))


def test_every_documented_keyword_is_parsed(table, spec):
    parsed = {(k.word, k.block) for k in table}
    extra = ["%s: `%s` in block `%s`" % (where(r), word_of(r.cells["keyword"]), word_of(r.cells["block"]))
             for r in spec if (word_of(r.cells["keyword"]), word_of(r.cells["block"])) not in parsed]
    assert not extra, "documented keywords the parser does not read in that block:\n" + "\n".join(extra)


def test_each_keyword_documented_once_per_block(spec):
    seen, twice = {}, []
    for r in spec:
        key = (word_of(r.cells["keyword"]), word_of(r.cells["block"]))
        if key in seen:
            twice.append("%s and line %d: `%s` in block `%s`" % (where(r), seen[key], key[0], key[1]))
        seen[key] = r.line
    assert not twice, "keywords with two rows in one block:\n" + "\n".join(twice)


def documented(spec):
    return {(word_of(r.cells["keyword"]), word_of(r.cells["block"])): r for r in spec}


def test_value_kinds_agree(table, spec):
    rows = documented(spec)
    problems = []
    for k in table:
        r = rows.get((k.word, k.block))
        if r is None:
            continue  # test_every_parsed_keyword_is_documented
        kind = documented_kind(r.cells["value"])
        if KINDS[k.value] != kind:
            problems.append("%s: the parser reads `%s`'s value as a %s (a value cell of kind %s), but the value "
                            "column '%s' is of kind %s" % (where(r), k.word, k.value, KINDS[k.value], r.cells["value"], kind))
        names = named_keywords(r.cells["value"])
        inside = [i.word for i in table if k.opens and i.block == k.opens]
        if (names or (k.value == "on/off" and inside)) and sorted(names) != sorted(inside):
            problems.append("%s: `%s` is followed by %s, but the value column names %s" % (
                where(r), k.word, ", ".join("`%s`" % w for w in inside) or "nothing",
                ", ".join("`%s`" % w for w in names) or "nothing"))
    assert not problems, "values the specification describes otherwise than the parser reads them:\n" + "\n".join(problems)


def test_defaults_agree(table, spec):
    rows = documented(spec)
    problems = []
    for k in table:
        r = rows.get((k.word, k.block))
        if r is not None and normalised_default(r.cells["default"]) != k.default:
            problems.append("%s: `%s`'s default is '%s' in the keyword table, '%s' in the specification" % (
                where(r), k.word, k.default, normalised_default(r.cells["default"])))
    assert not problems, "defaults that differ:\n" + "\n".join(problems)
