# SPDX-License-Identifier: AGPL-3.0-or-later
"""Every scene and include file of POV-Ray's own distribution that parses with Debian's
packaged povray must parse with ours (docs/specification.md, section 6).

Each item is parsed, not rendered: a wrapper scene #includes the file and then stops with
`#error "<marker>"`. Reaching the marker proves that the whole file parsed; the render
(photons, radiosity, tracing) never starts, so a scene costs its parse time plus POV-Ray's
fixed start-up (about 0.5 s per process on the unix front end).

Items:
  include   every *.inc under distribution/ (wrapper: `#version 3.7;`, colors.inc,
            shapes.inc, textures.inc, then the file)
  scene     every *.pov under distribution/, at clock 0
  ini       every scene that comes with an .ini (animations, portfolio, benchmark, desk):
            the .ini is passed first (its Declare=, clock and frame settings apply), then
            the wrapper; one item for its first and one for its last frame (+SF/+EF)
  menu      each [section] of the Windows "Insert Menu" Images.ini (Declare=Switch=N),
            which is how those .pov files and their .txt snippets are meant to be parsed

Modes (pytest options, tests/conftest.py):
  --compat-mode full  every item, with both binaries; writes <work>/report.tsv, prints the time
               each binary took and the list of items that fail with both (tests/compat/full-sweep).
  --compat-mode ci    the deterministic subset (every include item + every Nth other item of the
               sorted list, N = --compat-every); ours runs on each item and Debian's only on the
               items where ours fails (the question is only ever "does Debian parse it?").
  --compat-only REGEX: only items whose name matches; --compat-timeout: seconds per parse;
  --compat-known: fails_with_both.txt to compare the full sweep with.

Both programs run with the same user povray.conf (HOME points into the work directory) that
lets them read the distribution, and find the distribution's timrom.ttf under the names of
the Windows fonts the Insert Menu snippets use.

An item fails when Debian's povray reaches the marker and ours does not. Items that fail
with both binaries are listed (tests/compat/fails_with_both.txt holds the full sweep's list).
"""
import glob
import os
import re
import shutil

import plenoptic_testing as pt

MARKER = "COMPAT-PARSE-REACHED-END"
# Include files are parsed after the three that POV-Ray's documentation tells a scene to
# include first (stones.inc, skies.inc, shapes2.inc, ... use their colours and shapes); each
# of the three has an include guard, so it is harmless when it is the item itself.
INCLUDE_PRELUDE = '#include "colors.inc"\n#include "shapes.inc"\n#include "textures.inc"\n'


class Item:
    def __init__(self, kind, ident, wrapper, libdirs, pre_args=(), post_args=()):
        self.kind = kind          # include | scene | ini | menu
        self.ident = ident        # stable name, relative to distribution/
        self.wrapper = wrapper    # text of the wrapper scene
        self.libdirs = libdirs    # +L directories (the item's own folder first)
        self.pre_args = list(pre_args)    # before +I (an .ini file)
        self.post_args = list(post_args)  # after everything (+SF/+EF)


def sdl_string(path):
    return path.replace("\\", "/")


def ini_settings(path):
    """key -> value of a POV-Ray .ini (top section only), keys lower-cased."""
    out = {}
    with open(path, errors="replace") as f:
        for line in f:
            line = line.split(";")[0].strip()
            if line.startswith("["):
                break
            if "=" in line:
                k, v = line.split("=", 1)
                out.setdefault(k.strip().lower(), v.strip().strip('"'))
    return out


def enumerate_items(dist):
    items = []
    inc_dir = os.path.join(dist, "include")
    files = []
    for root, dirs, names in os.walk(dist):
        dirs.sort()
        for n in sorted(names):
            files.append(os.path.join(root, n))
    for path in files:
        rel = os.path.relpath(path, dist)
        here = os.path.dirname(path)
        if path.endswith(".inc"):
            w = '#version 3.7;\n%s#include "%s"\n#error "%s"\n' % (INCLUDE_PRELUDE, sdl_string(path), MARKER)
            items.append(Item("include", rel, w, [here, inc_dir]))
        elif path.endswith(".pov"):
            w = '#include "%s"\n#error "%s"\n' % (sdl_string(path), MARKER)
            items.append(Item("scene", rel, w, [here, inc_dir]))
    # Scenes that come with an .ini naming them.
    for ini in sorted(glob.glob(os.path.join(dist, "scenes", "**", "*.ini"), recursive=True)):
        s = ini_settings(ini)
        pov = s.get("input_file_name")
        if not pov:
            continue
        scene = os.path.join(os.path.dirname(ini), pov)
        if not os.path.exists(scene):
            continue
        first = int(float(s.get("initial_frame", "1")))
        last = int(float(s.get("final_frame", str(first))))
        frames = [first] if last == first else [first, last]
        here = os.path.dirname(ini)
        for fr in frames:
            w = '#include "%s"\n#error "%s"\n' % (sdl_string(scene), MARKER)
            ident = "%s@frame%d" % (os.path.relpath(ini, dist), fr)
            items.append(Item("ini", ident, w, [here, inc_dir], pre_args=[ini],
                              post_args=["+SF%d" % fr, "+EF%d" % fr]))
    # The Windows Insert Menu: Images.ini[N] sets Switch=N for Images.pov.
    menu = os.path.join(dist, "platform-specific", "windows", "Insert Menu")
    images_ini = os.path.join(menu, "Images.ini")
    if os.path.exists(images_ini):
        section = None
        with open(images_ini, errors="replace") as f:
            for line in f:
                line = line.split(";")[0].strip()
                m = re.match(r"^\[(.+)\]$", line)
                if m:
                    section = m.group(1)
                    continue
                m = re.match(r"^Declare\s*=\s*Switch\s*=\s*(\S+)$", line, re.I)
                if m and section is not None:
                    w = ('#declare Switch = %s;\n#include "%s"\n#error "%s"\n'
                         % (m.group(1), sdl_string(os.path.join(menu, "Images.pov")), MARKER))
                    ident = "%s[%s]" % (os.path.relpath(images_ini, dist), section)
                    items.append(Item("menu", ident, w, [menu, inc_dir]))
                    section = None
    items.sort(key=lambda it: (it.kind, it.ident))
    return items


def ci_subset(items, every):
    """Every include; every Nth item of each other kind, counted from the first."""
    out = []
    counters = {}
    for it in items:
        if it.kind == "include":
            out.append(it)
            continue
        n = counters.get(it.kind, 0)
        counters[it.kind] = n + 1
        if n % every == 0:
            out.append(it)
    return out


def safe_name(ident):
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", ident)


def prepare_home(work, dist):
    """A HOME whose user povray.conf lets both binaries read the distribution wherever it is."""
    home = os.path.join(work, "home")
    conf_dir = os.path.join(home, ".povray", "3.7")
    os.makedirs(conf_dir, exist_ok=True)
    os.makedirs(os.path.join(work, "links"), exist_ok=True)
    with open(os.path.join(conf_dir, "povray.conf"), "w") as f:
        f.write("[Permitted Paths]\nread* = %s\nread* = %s\n" % (dist, os.path.join(work, "links")))
    return home


# Windows fonts that the Insert Menu's snippets name; the distribution's own timrom.ttf
# stands in for them (for both programs alike), so those snippets parse instead of stopping
# at "Cannot open font file".
WINDOWS_FONTS = ("arial.ttf", "arialbd.ttf")


def prepare_fonts(work, dist):
    fonts = os.path.join(work, "links", "fonts")
    os.makedirs(fonts, exist_ok=True)
    for name in WINDOWS_FONTS:
        link = os.path.join(fonts, name)
        if not os.path.islink(link):
            os.symlink(os.path.join(dist, "include", "timrom.ttf"), link)
    return fonts


def no_spaces(path, work):
    """POV-Ray splits a command-line option at spaces: reach such a folder through a link."""
    if " " not in path:
        return path
    link = os.path.join(work, "links", safe_name(os.path.basename(path)))
    if not os.path.islink(link):
        os.symlink(path, link)
    return link


def parse_once(povray, item, work, home, fonts, timeout):
    """-> (status, seconds, message); status is ok | error | timeout."""
    d = os.path.join(work, "items", safe_name(item.ident))
    if os.path.exists(d):
        shutil.rmtree(d)
    os.makedirs(d)
    with open(os.path.join(d, "wrapper.pov"), "w") as f:
        f.write(item.wrapper)
    cmd = [povray] + item.pre_args + ["+Iwrapper.pov", "+Oout.png", "+W8", "+H6", "-D", "-P",
                                      "-GS", "-GR", "-GW"]
    cmd += ["+L" + no_spaces(p, work) for p in item.libdirs] + ["+L" + fonts] + item.post_args
    env = dict(os.environ, HOME=home)
    try:
        res = pt.run_process(cmd, cwd=d, env=env, timeout=timeout)
    except OSError as e:  # the program itself cannot run: no verdict on the item
        raise AssertionError("cannot run %s: %s" % (povray, e))
    if res.timed_out:
        return "timeout", res.seconds, "no end of parse within %d s" % timeout
    if MARKER in res.output:
        shutil.rmtree(d, ignore_errors=True)
        return "ok", res.seconds, ""
    return "error", res.seconds, pt.first_error(res.output, res.returncode)


def test_parse_distribution(args):
    reference = pt.require_debian_povray(args.reference_povray)
    assert args.upstream, "no --upstream (the unpacked Debian POV-Ray source)"
    mode, every, timeout = args.compat_mode, int(args.compat_every), int(args.compat_timeout)
    known, only = args.compat_known, args.compat_only
    assert mode in ("ci", "full"), "--compat-mode is ci or full, not %r" % mode
    dist = os.path.abspath(os.path.join(args.upstream, "distribution"))
    work = args.work
    home = prepare_home(work, dist)
    fonts = prepare_fonts(work, dist)

    items = enumerate_items(dist)
    counts = {}
    for it in items:
        counts[it.kind] = counts.get(it.kind, 0) + 1
    chosen = items if mode == "full" else ci_subset(items, every)
    if only:
        chosen = [it for it in chosen if re.search(only, it.ident)]
    print("distribution: %s" % dist)
    print("items: %s; this run (%s): %d" % (", ".join("%d %s" % (counts[k], k) for k in sorted(counts)),
                                           mode, len(chosen)))
    assert chosen, "no item to parse (is %s POV-Ray's distribution folder?)" % dist

    regressions, both, only_ours, rows = [], [], [], []
    t_ours = t_ref = 0.0
    report = open(os.path.join(work, "report.tsv"), "w")
    report.write("kind\titem\tours\tdebian\tours_seconds\tdebian_seconds\tours_message\tdebian_message\n")
    for it in chosen:
        s_ours, dt_ours, m_ours = parse_once(args.povray, it, work, home, fonts, timeout)
        t_ours += dt_ours
        s_ref, dt_ref, m_ref = None, 0.0, ""
        if mode == "full" or s_ours != "ok":
            s_ref, dt_ref, m_ref = parse_once(reference, it, work, home, fonts, timeout)
            t_ref += dt_ref
        row = (it.kind, it.ident, s_ours, s_ref or "-", "%.2f" % dt_ours, "%.2f" % dt_ref, m_ours, m_ref)
        rows.append(row)
        report.write("\t".join(row) + "\n")
        report.flush()
        if s_ours != "ok" and s_ref == "ok":
            regressions.append(it)
            print("FAIL %s: Debian's povray parses it, ours does not: %s" % (it.ident, m_ours))
        elif s_ours != "ok":
            both.append((it.ident, m_ref))
        elif s_ref not in (None, "ok"):
            only_ours.append((it.ident, m_ref))

    report.close()
    print("")
    print("parse time: ours %.1f s over %d items; Debian's %.1f s over %d items"
          % (t_ours, len(chosen), t_ref, sum(1 for r in rows if r[3] != "-")))
    if both:
        print("%d item(s) fail with both binaries (not a regression):" % len(both))
        for ident, msg in both:
            print("  both  %s: %s" % (ident, msg))
    if only_ours:
        print("%d item(s) parse with ours only:" % len(only_ours))
        for ident, msg in only_ours:
            print("  ours-only  %s: Debian says %s" % (ident, msg))
    if mode == "full":
        listing = os.path.join(work, "fails_with_both.txt")
        with open(listing, "w") as f:
            for ident, _ in both:
                f.write(ident + "\n")
        print("list of items failing with both written to %s" % listing)
        if known and os.path.exists(known) and not only:
            with open(known) as f:
                listed = set(l.strip() for l in f if l.strip() and not l.startswith("#"))
            now = set(i for i, _ in both)
            if listed != now:
                print("note: %s differs from this sweep: new %s, gone %s"
                      % (known, sorted(now - listed), sorted(listed - now)))
    print("%d parsed, %d fail with both, %d regression(s)"
          % (len(chosen) - len(both) - len(regressions), len(both), len(regressions)))
    assert not regressions, ("%d item(s) that Debian's povray parses and ours does not: %s"
                             % (len(regressions), ", ".join(it.ident for it in regressions)))
