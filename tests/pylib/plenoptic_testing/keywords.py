# SPDX-License-Identifier: AGPL-3.0-or-later
"""The plenoptic camera's keyword table, the one its parser reads every block through
(source/povray_glue/plenoptic_keywords.h), as the program plenoptic-keyword-table (built beside
povray from the same table, tests/docs/plenoptic_keyword_table.cpp) lists it."""
import os
import subprocess
from typing import List, NamedTuple

COLUMNS = ["word", "block", "value", "opens", "reserved", "default", "doc"]


class Keyword(NamedTuple):
    word: str      # the keyword
    block: str     # where it is written: camera, main_lens, ..., white_image, diffraction
    value: str     # how its value is read: flag, number, vector2, vector3, on/off, word, string, block, ...
    opens: str     # block and on/off rows: the block (of keywords or modifiers) that follows; else ""
    reserved: bool  # one of POV-Ray's own reserved words (else a word only inside the camera)
    default: str   # as the specification's "default" column states it; "" when none
    doc: str       # one line


def program(build_dir: str) -> str:
    return os.path.join(build_dir, "plenoptic-keyword-table")


def keyword_table(build_dir: str) -> List[Keyword]:
    """Every row of the table, in the table's order."""
    exe = program(build_dir)
    assert os.access(exe, os.X_OK), "%s is missing: build the project first (tools/build)" % exe
    out = subprocess.run([exe], check=True, stdout=subprocess.PIPE, universal_newlines=True).stdout
    lines = out.splitlines()
    assert lines and lines[0].split("\t") == COLUMNS, "unexpected header from %s: %r" % (exe, lines[:1])
    rows = []
    for line in lines[1:]:
        cells = line.split("\t")
        assert len(cells) == len(COLUMNS), "%s: a row of %d cells: %r" % (exe, len(cells), line)
        assert cells[4] in ("yes", "no"), line
        rows.append(Keyword(cells[0], cells[1], cells[2], cells[3], cells[4] == "yes", cells[5], cells[6]))
    return rows
