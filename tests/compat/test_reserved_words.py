# SPDX-License-Identifier: AGPL-3.0-or-later
"""Do the reserved words our patches add collide with any identifier in POV-Ray's distribution?

A new reserved word breaks every scene that uses the same name as an identifier
(`#declare pitch = ...`, a macro parameter, a use in an expression, `Declare=pitch=1` in an
.ini). This scans every SDL file of distribution/ with a small tokenizer that skips comments
(nested /* */ and //) and strings, and fails on any occurrence of a new word as a token.

The new words are not copied from anywhere: they are the difference between the reserved
word table of the upstream source and that of our patched source.
"""
import os
import re

import pytest

TABLE_ENTRY = re.compile(r'\{\s*[A-Z0-9_]+_TOKEN\s*,\s*"([^"]+)"\s*\}')
IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
# .txt files that are prose, not SDL snippets.
PROSE = {"agpl-3.0.txt", "readme.txt", "user-keywords.txt", "teapot.txt"}


def reserved_words(reswords_cpp):
    with open(reswords_cpp, errors="replace") as f:
        return set(TABLE_ENTRY.findall(f.read()))


def sdl_tokens(text):
    """(word, line) for every identifier-like token outside comments and strings;
    also (word, line, where) for words inside comments/strings, where = comment|string."""
    code, other = [], []
    i, n, line = 0, len(text), 1
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            other += [(w, line, "comment") for w in IDENT.findall(text[i:j])]
            i = j
        elif text.startswith("/*", i):
            depth, j, start_line = 1, i + 2, line  # POV-Ray's block comments nest
            while j < n and depth > 0:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            chunk = text[i:j]
            other += [(m.group(0), start_line + chunk.count("\n", 0, m.start()), "comment")
                      for m in IDENT.finditer(chunk)]
            line += chunk.count("\n")
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"' and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            chunk = text[i:j + 1]
            other += [(w, line, "string") for w in IDENT.findall(chunk)]
            i = j + 1
        else:
            m = IDENT.match(text, i)
            if m:
                code.append((m.group(0), line))
                i = m.end()
            elif c.isdigit() or c == ".":
                m = re.compile(r"[0-9.]+([eE][-+]?[0-9]+)?").match(text, i)
                i = m.end() if m else i + 1
            else:
                i += 1
    return code, other


def ini_declared_names(text):
    """(name, line) of every Declare=NAME=value in an .ini (comments start with ';')."""
    out = []
    for k, raw in enumerate(text.splitlines(), 1):
        line = raw.split(";")[0]
        for m in re.finditer(r"(?:^|\s)Declare\s*=\s*([A-Za-z_][A-Za-z0-9_]*)\s*=", line, re.I):
            out.append((m.group(1), k))
    return out


def sdl_files(dist):
    for root, dirs, names in os.walk(dist):
        dirs.sort()
        for n in sorted(names):
            low = n.lower()
            path = os.path.join(root, n)
            if low.endswith((".pov", ".inc", ".mcr")):
                yield path, "sdl"
            elif low.endswith(".txt") and low not in PROSE:
                yield path, "sdl"     # Insert Menu and templates/ snippets
            elif low.endswith(".ini"):
                yield path, "ini"


@pytest.fixture(scope="module")
def added(args):
    """The reserved words our patches add (tables of --upstream and --patched-source)."""
    assert args.upstream and args.patched_source, "need --upstream and --patched-source"
    old = reserved_words(os.path.join(args.upstream, "source", "backend", "parser", "reswords.cpp"))
    new = reserved_words(os.path.join(args.patched_source, "source", "backend", "parser", "reswords.cpp"))
    assert len(old) >= 300 and len(new) >= len(old), (
        "could not read the reserved word tables (%d upstream, %d patched words)" % (len(old), len(new)))
    removed = sorted(old - new)
    assert not removed, "our patches remove upstream reserved words: %s" % " ".join(removed)
    words = sorted(new - old)
    print("reserved words added by our patches (%d): %s" % (len(words), " ".join(words)))
    assert words, "no new reserved word found: is --patched-source the patched tree?"
    return words


def test_only_plenoptic_is_added(added):
    # Only the camera's type word may be global; every other word of the camera is read in
    # context (docs/specification.md, section 6; source/povray_glue/parse_plenoptic.cpp).
    assert added == ["plenoptic"], ("our patches may add only 'plenoptic' to POV-Ray's reserved words; they add: %s"
                                    % " ".join(added))


def test_no_new_word_is_an_identifier(args, added):
    distribution = os.path.join(args.upstream, "distribution")
    added_set = set(added)
    lower = {w.lower(): w for w in added}

    collisions, harmless, case_only = [], {}, {}
    nfiles = 0
    for path, kind in sdl_files(distribution):
        nfiles += 1
        rel = os.path.relpath(path, distribution)
        with open(path, errors="replace") as f:
            text = f.read()
        if kind == "ini":
            for w, line in ini_declared_names(text):
                if w in added_set:
                    collisions.append("%s:%d: Declare=%s" % (rel, line, w))
            continue
        code, other = sdl_tokens(text)
        for w, line in code:
            if w in added_set:
                collisions.append("%s:%d: '%s' used as an identifier" % (rel, line, w))
            elif w.lower() in lower:
                case_only.setdefault(w, []).append("%s:%d" % (rel, line))
        for w, line, where in other:
            if w in added_set:
                harmless.setdefault(w, []).append("%s:%d (%s)" % (rel, line, where))

    print("scanned %d SDL and .ini files of %s" % (nfiles, distribution))
    for w in sorted(harmless):
        print("  harmless: '%s' inside comments/strings: %s" % (w, ", ".join(harmless[w])))
    for w in sorted(case_only):
        print("  harmless: '%s' differs from reserved '%s' in case (SDL is case-sensitive): %s"
              % (w, lower[w.lower()], ", ".join(case_only[w][:5])))
    assert nfiles > 0, "no SDL file found in %s" % distribution
    assert not collisions, ("%d use(s) of a new reserved word as an identifier:\n  %s"
                            % (len(collisions), "\n  ".join(collisions)))
