# SPDX-License-Identifier: AGPL-3.0-or-later
"""Instruction counts of a render from valgrind's callgrind: these repeat exactly whatever else
the machine is doing, unlike the wall clock."""
import re
import shutil
import subprocess

from .util import log


def have_callgrind():
    return bool(shutil.which("valgrind") and shutil.which("callgrind_annotate"))


# The functions whose inclusive instruction counts split a render into its parts (POV-Ray 3.7's
# names, as callgrind prints them for a build without debug information or with it).
TRACE_PIXEL_FN = "pov::TracePixel::operator()(double, double, double, double, pov_base::GenericColour<float>&)"
TRACE_RAY_FN = ("pov::Trace::TraceRay(pov::Ray const&, pov_base::GenericColour<float>&, float, "
                "pov::Trace::TraceTicket&, bool, double)")


def callgrind_inclusive(path):
    """{function: inclusive instructions} and the program total, from callgrind_annotate.
    A recursive call shows as a separate name with a suffix ('2, '3, ...), so the plain name is
    the outermost call only."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", path],
                          check=True, capture_output=True, text=True).stdout
    total = None
    inclusive = {}
    for line in text.splitlines():
        m = re.match(r"\s*([0-9,]+)\s+\(\s*[0-9.]+%\)\s+(.*)$", line)
        if not m:
            continue
        n, rest = int(m.group(1).replace(",", "")), m.group(2)
        if rest.startswith("PROGRAM TOTALS"):
            total = n
            continue
        rest = re.sub(r" \[[^\]]*\]$", "", rest)  # the object file
        for fn in (TRACE_PIXEL_FN, TRACE_RAY_FN):
            if rest.endswith(":" + fn):  # "file:function"; a recursion level ends in 'N instead
                inclusive[fn] = inclusive.get(fn, 0) + n
    return total, inclusive


def callgrind_calls(path, fn):
    """(calls, instructions inside those calls) of function fn, summed over its callers, from the
    raw callgrind file: each call arc is a `cfn=` line, then `calls=COUNT ...`, then the arc's
    inclusive cost. Names are compressed: `(id) name` the first time, `(id)` after."""
    names = {}
    target = None
    calls = cost = 0
    expect_cost = False
    with open(path, errors="replace") as f:
        for line in f:
            if expect_cost:
                expect_cost = False
                fields = line.split()
                if len(fields) >= 2:
                    cost += int(fields[1])
                continue
            m = re.match(r"(c?fn)=(?:\((\d+)\))? ?(.*)$", line.rstrip("\n"))
            if m:
                name = m.group(3)
                if m.group(2) is not None:
                    if name:
                        names[m.group(2)] = name
                    name = names.get(m.group(2), "")
                if m.group(1) == "cfn":
                    target = name
                continue
            if line.startswith("calls="):
                if target == fn:
                    calls += int(line[6:].split()[0])
                    expect_cost = True
                target = None
    return calls, cost


def callgrind_counts(path, pixels):
    """Total instructions; per-pixel work (inclusive TracePixel::operator(): everything done for
    the pixels); scene (inclusive outermost Trace::TraceRay and its number of calls: the rays
    traced into the scene); camera instructions per pixel = (per-pixel work - scene) / pixels."""
    total, inclusive = callgrind_inclusive(path)
    work = inclusive.get(TRACE_PIXEL_FN)
    scene = inclusive.get(TRACE_RAY_FN, 0)  # 0: no ray reached the scene
    if total is None or work is None:
        raise RuntimeError("callgrind: no totals or no %s in %s" % (TRACE_PIXEL_FN, path))
    calls, arc_cost = callgrind_calls(path, TRACE_RAY_FN)
    if arc_cost != scene:
        log("  callgrind: TraceRay inclusive %d by annotate, %d summed over its call arcs" % (scene, arc_cost))
    return {"total_ir": total, "pixel_work_ir": work, "trace_ray_ir": scene, "trace_ray_calls": calls,
            "pixels": pixels, "camera_ir_per_pixel": (work - scene) / pixels}
