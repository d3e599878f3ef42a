# SPDX-License-Identifier: AGPL-3.0-or-later
"""Shared helpers of the robustness tests: scenes around a camera block, running povray with a
time limit, reading POV-Ray's parse errors, spotting crashes, reading OpenEXR floats."""
import os
import re
import signal
import subprocess
import sys
import time

# The world every robustness scene shows; only the camera changes from case to case.
WORLD = """\
light_source { <-3, 5, -4> color rgb 1 }
light_source { <4, 3, -2> color rgb 0.3 shadowless }
sky_sphere { pigment { gradient y color_map { [0 rgb <0.75, 0.85, 1>] [1 rgb <0.3, 0.45, 0.8>] } } }
plane { y, 0 pigment { checker color rgb 0.9 color rgb 0.2 scale 0.25 } }
sphere { <0, 0.3, 0>, 0.3 pigment { color rgb <0.9, 0.3, 0.2> } finish { specular 0.4 } }
box { <-0.9, 0, 0.8>, <-0.5, 0.5, 1.0> pigment { color rgb <0.2, 0.5, 0.9> } }
"""

HEADER = "// SPDX-License-Identifier: AGPL-3.0-or-later\n#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n"


def scene_text(camera_block):
    """A whole scene: header, the given camera block (text, verbatim), the world."""
    return HEADER + camera_block.rstrip("\n") + "\n" + WORLD


def write_scene(path, camera_block):
    with open(path, "w") as f:
        f.write(scene_text(camera_block))


class Run:
    """Outcome of one povray process."""

    def __init__(self, returncode, output, seconds, timed_out):
        self.returncode = returncode
        self.output = output
        self.seconds = seconds
        self.timed_out = timed_out


def run_povray(povray, scene, out, width, height, extra=(), timeout=60, cwd=None):
    """Runs povray on `scene` writing `out`; kills the whole process group at the time limit."""
    cmd = [povray, "+I" + scene, "+O" + out, "+W%d" % width, "+H%d" % height,
           "-D", "-P", "-GS", "-GR"] + list(extra)
    start = time.monotonic()
    proc = subprocess.Popen(cmd, cwd=cwd or os.path.dirname(os.path.abspath(out)),
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        output, _ = proc.communicate(timeout=timeout)
        timed_out = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        output, _ = proc.communicate()
        timed_out = True
    return Run(proc.returncode, output.decode("utf-8", errors="replace"),
               time.monotonic() - start, timed_out)


# POV-Ray 3.7 prints "File 'scene.pov' line 12: Parse Error: message"; older releases printed
# "File: scene.pov  Line: 12". Both are accepted.
_ERROR_37 = re.compile(r"^File '(?P<file>[^']*)' line (?P<line>\d+): (?P<kind>Parse Error|[A-Za-z ]*Error): ?(?P<rest>.*)$")
_ERROR_OLD = re.compile(r"^File: (?P<file>\S+)\s+Line: (?P<line>\d+)")


def parse_error(output):
    """(file, line, message) of the first parse error in povray's output, or None.
    The message is POV-Ray's wrapped text joined into one line."""
    lines = output.splitlines()
    for n, text in enumerate(lines):
        m = _ERROR_37.match(text) or _ERROR_OLD.match(text)
        if not m:
            continue
        parts = [m.groupdict().get("rest") or ""]
        for follow in lines[n + 1:]:
            if follow.startswith(("Fatal error", "Render failed", "Parse Error", "File ")) or not follow.strip():
                break
            parts.append(follow.strip())
        message = re.sub(r"\s+", " ", " ".join(p.strip() for p in parts)).strip()
        return m.group("file"), int(m.group("line")), message
    return None


CRASH_MARKERS = ("Segmentation", "core dumped", "Aborted", "terminate called", "Bus error",
                 "Floating point exception", "AddressSanitizer", "runtime error:", "Assertion")


def crash_reason(run):
    """Why a run counts as a crash or hang (None when it ended by itself with an exit status)."""
    if run.timed_out:
        return "did not finish within the time limit (killed after %.0f s)" % run.seconds
    if run.returncode < 0:
        return "killed by signal %d" % -run.returncode
    if run.returncode >= 128:
        return "exit status %d (a signal)" % run.returncode
    for marker in CRASH_MARKERS:
        if marker in run.output:
            return "output mentions %r" % marker
    return None


def refusal_problems(run):
    """For a run that must be refused at parse time: its problems (a crash, exit 0, no
    `File ... line ...` parse error) and that parse error as (file, line, message), or None."""
    problems = []
    crash = crash_reason(run)
    if crash:
        problems.append("crashed: " + crash)
    if run.returncode == 0:
        problems.append("accepted (exit 0): the scene must be refused")
    err = parse_error(run.output)
    if err is None:
        problems.append("no 'File ... line ...' parse error in the output")
    return problems, err


def read_exr(path):
    """The float pixels (H, W, channels) of an OpenEXR file."""
    import OpenImageIO as oiio
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise RuntimeError("cannot read %s: %s" % (path, buf.geterror()))
    return buf.get_pixels(oiio.FLOAT)


def read_image(path):
    """Pixels of any image OpenImageIO reads (PNG as 0..1 floats)."""
    return read_exr(path)


def load_json_strict(path):
    """The metadata JSON, read strictly (no NaN or Infinity, which Python's json would otherwise
    accept, no duplicate key, UTF-8 only) and checked against docs/metadata.schema.json
    (tests/metadata/metadata_schema.py); a ValueError naming the file and the problem."""
    shared = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "metadata")
    if shared not in sys.path:
        sys.path.insert(0, shared)
    import metadata_schema
    return metadata_schema.load(path)


def tail(text, n=15):
    return "\n".join("    | " + t for t in text.rstrip().splitlines()[-n:])
