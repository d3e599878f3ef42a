# SPDX-License-Identifier: AGPL-3.0-or-later
"""The repository is self-contained: no tracked file points outside it, and no Markdown link
is broken.

Checks every file that git tracks (`git ls-files` in the source directory, so a new file counts
once it is added), except *.patch files (they quote POV-Ray's own sources) and binary files:

1. No file names a path of the development machine outside the checkout: the design
   directory that docs/specification.md replaced, a `shared` folder beside the checkout
   (`..` then `shared`), or an absolute path under the machine's work directory. The
   patterns are built below from pieces, so this file does not match itself.
2. In every tracked .md file, every relative link `[text](target)` or `[label]: target`
   (outside code spans and fenced code blocks) points to a tracked file or directory inside
   the repository, and its `#anchor`, when there is one and the target is a Markdown file,
   names a heading of that file (GitHub's rule: lower case, punctuation dropped, spaces
   become hyphens).

The test fails with one `file:line: message` per problem, and is skipped when the source
directory (--source-dir, default this checkout) is not a git checkout (ctest then reports it as
skipped).
"""
import os
import re
import subprocess

import pytest

# 1. Paths outside the repository. The work directory counts only as the start of an absolute
# path, not after a name (a build folder's own `work` subfolder is fine).
_W = "work"
OUTSIDE = [
    (re.compile(re.escape("shared" + "/design")), "names the design directory outside the repository"),
    (re.compile(re.escape(".." + "/shared")), "names a shared folder outside the repository"),
    (re.compile(re.escape("/" + _W + "/shared")), "names a shared folder outside the repository"),
    (re.compile(r"(?<![\w.$}\-/])/" + _W + "/"), "names an absolute path outside the repository"),
]

# 2. Markdown links.
INLINE_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*(<[^>]*>|[^\s()]*(?:\([^\s()]*\)[^\s()]*)*)(?:\s+[\"'(][^)]*)?\)")
REFERENCE_DEF = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1")
FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})")
HEADING = re.compile(r"^ {0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
HTML_ANCHOR = re.compile(r"<a\s+(?:[^>]*\s)?(?:id|name)\s*=\s*[\"']([^\"']+)[\"']", re.I)
SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.\-]*:")


def tracked_files(root):
    """Paths (relative, '/'-separated) that git tracks in `root`, or None outside a checkout."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "-z"], check=True,
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    return [p for p in out.decode("utf-8", "surrogateescape").split("\0") if p]


def read_text(path):
    """The file's text, or None for a binary (NUL byte or not UTF-8) or missing file."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return None
    if b"\0" in data[:65536]:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def markdown_lines(text, keep_code_spans=False):
    """(line number, line) of the lines outside fenced code blocks, code spans blanked
    unless `keep_code_spans` (a heading's code spans are part of its anchor)."""
    fence = None
    for number, line in enumerate(text.split("\n"), 1):
        m = FENCE.match(line)
        if fence is None and m:
            fence = m.group(1)[0] * len(m.group(1))
            continue
        if fence is not None:
            if m and m.group(1)[0] == fence[0] and len(m.group(1)) >= len(fence):
                fence = None
            continue
        yield number, line if keep_code_spans else CODE_SPAN.sub(lambda s: " " * len(s.group(0)), line)


def slug(heading):
    """GitHub's anchor for a heading's text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)   # a link shows its text only
    text = re.sub(r"<[^>]+>", "", text).strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(text):
    """Every anchor a Markdown file defines: its headings' slugs (repeats get -1, -2, ...)
    and explicit <a id/name="..."> anchors."""
    found, seen = set(), {}
    for _, line in markdown_lines(text, keep_code_spans=True):
        m = HEADING.match(line)
        if m:
            base = slug(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else "%s-%d" % (base, n))
        found.update(HTML_ANCHOR.findall(line))
    return found


def link_targets(line):
    for m in INLINE_LINK.finditer(line):
        yield m.group(1)
    m = REFERENCE_DEF.match(line)
    if m:
        yield m.group(1)


def test_self_contained(args):
    root = os.path.abspath(args.source_dir)
    files = tracked_files(root)
    if files is None:
        pytest.skip("check_self_contained: %s is not a git checkout; nothing checked" % root)
    tracked = set(files)
    directories = {os.path.dirname(p) for p in files}
    for p in list(directories):
        while p:
            p = os.path.dirname(p)
            directories.add(p)
    texts = {}
    problems = []

    def text_of(rel):
        if rel not in texts:
            texts[rel] = read_text(os.path.join(root, rel))
        return texts[rel]

    for rel in sorted(files):
        if rel.endswith(".patch"):
            continue
        text = text_of(rel)
        if text is None:
            continue
        for number, line in enumerate(text.split("\n"), 1):
            for pattern, message in OUTSIDE:
                if pattern.search(line):
                    problems.append("%s:%d: %s: %s" % (rel, number, message, line.strip()))
                    break
        if not rel.endswith(".md"):
            continue
        for number, line in markdown_lines(text):
            for target in link_targets(line):
                target = target.strip("<>")
                if not target or SCHEME.match(target) or target.startswith("//"):
                    continue
                path, _, anchor = target.partition("#")
                path = path.split("?")[0]
                if path:
                    base = "" if path.startswith("/") else os.path.dirname(rel)
                    resolved = os.path.normpath(os.path.join(base, path.lstrip("/"))).replace(os.sep, "/")
                    if resolved == ".":
                        resolved = ""
                    if resolved == ".." or resolved.startswith("../"):
                        problems.append("%s:%d: link to '%s' leaves the repository" % (rel, number, target))
                        continue
                    if resolved not in tracked and resolved not in directories:
                        problems.append("%s:%d: link to '%s': no such file in the repository" % (rel, number, target))
                        continue
                else:
                    resolved = rel
                if anchor and resolved.endswith(".md"):
                    target_text = text_of(resolved)
                    if target_text is not None and anchor not in anchors(target_text):
                        problems.append("%s:%d: link to '%s': %s has no heading with anchor '#%s'"
                                        % (rel, number, target, resolved, anchor))

    assert not problems, ("%d problem(s) in %d tracked files:\n%s"
                          % (len(problems), len(files), "\n".join(problems)))
    print("check_self_contained: %d tracked files, no reference outside the repository, "
          "no broken Markdown link" % len(files))
