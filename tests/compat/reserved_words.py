#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Do the reserved words our patches add collide with any identifier in POV-Ray's distribution?

A new reserved word breaks every scene that uses the same name as an identifier
(`#declare pitch = ...`, a macro parameter, a use in an expression, `Declare=pitch=1` in an
.ini). This scans every SDL file of distribution/ with a small tokenizer that skips comments
(nested /* */ and //) and strings, and fails on any occurrence of a new word as a token.

The new words are not copied from anywhere: they are the difference between the reserved
word table of the upstream source and that of our patched source.
"""
import argparse
import os
import re
import sys

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


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--distribution", required=True, help="UPSTREAM_DIR/distribution")
    ap.add_argument("--upstream-reswords", required=True, help="reswords.cpp of the unpatched source")
    ap.add_argument("--patched-reswords", required=True, help="reswords.cpp of our patched source")
    args = ap.parse_args()

    old = reserved_words(args.upstream_reswords)
    new = reserved_words(args.patched_reswords)
    if len(old) < 300 or len(new) < len(old):
        print("FAIL: could not read the reserved word tables (%d upstream, %d patched words)"
              % (len(old), len(new)))
        return 1
    added = sorted(new - old)
    removed = sorted(old - new)
    print("reserved words added by our patches (%d): %s" % (len(added), " ".join(added)))
    if removed:
        print("FAIL: our patches remove upstream reserved words: %s" % " ".join(removed))
        return 1
    if not added:
        print("FAIL: no new reserved word found: is --patched-reswords the patched file?")
        return 1
    # Only the camera's type word may be global; every other word of the camera is read in
    # context (docs/specification.md, section 6; source/povray_glue/parse_plenoptic.cpp).
    if added != ["plenoptic"]:
        print("FAIL: our patches may add only 'plenoptic' to POV-Ray's reserved words; they add: %s"
              % " ".join(added))
        return 1
    added_set = set(added)
    lower = {w.lower(): w for w in added}

    collisions, harmless, case_only = [], {}, {}
    nfiles = 0
    for path, kind in sdl_files(args.distribution):
        nfiles += 1
        rel = os.path.relpath(path, args.distribution)
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

    print("scanned %d SDL and .ini files of %s" % (nfiles, args.distribution))
    for w in sorted(harmless):
        print("  harmless: '%s' inside comments/strings: %s" % (w, ", ".join(harmless[w])))
    for w in sorted(case_only):
        print("  harmless: '%s' differs from reserved '%s' in case (SDL is case-sensitive): %s"
              % (w, lower[w.lower()], ", ".join(case_only[w][:5])))
    if collisions:
        print("FAIL: %d use(s) of a new reserved word as an identifier:" % len(collisions))
        for c in collisions:
            print("  " + c)
        return 1
    print("ok: no new reserved word is used as an identifier anywhere in the distribution")
    return 0


if __name__ == "__main__":
    sys.exit(main())
