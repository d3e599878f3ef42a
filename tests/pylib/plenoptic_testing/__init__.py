# SPDX-License-Identifier: AGPL-3.0-or-later
"""The one shared helper of the render and tool tests (tests/*/test_*.py, run by pytest).

What it holds, in sections:
  - running povray (ours, and Debian's /usr/bin/povray where a test compares with it) with a
    time limit, capturing its output, reading POV-Ray's error messages, spotting crashes;
  - writing scenes and rendering them (the command lines each family used, as named presets);
  - reading images and OpenEXR files with OpenImageIO, writing a PNG to look at, idiff;
  - the render's metadata (<image>.plenoptic.json): strict JSON (UTF-8 only, no lone surrogate,
    no duplicate key, no NaN or Infinity) validated against docs/metadata.schema.json;
Running a process, reading an image and reading the metadata go through the decoder package's
one runner (plenoptic_lf.povray), image reader (plenoptic_lf.images) and metadata reader
(plenoptic_lf.metadata): python/ is on sys.path (tests/conftest.py puts it there).
  - the optics of docs/specification.md written out again, independently of the code under
    test (thin lens, lattices, poses, sensor <-> pixel);
  - image measurements on scipy.ndimage: connected components, centroids, dilation, box blur;
  - plenoptic-project.

The test options (--povray, --work, ...) come from tests/conftest.py. Everything a test expects
is computed here or in the test from the specification, never by calling the camera code.
"""
import json
import math
import os
import re
import shutil
import subprocess
import sys

import numpy as np

TESTS_DIR = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
SOURCE_DIR = os.path.dirname(TESTS_DIR)
DEBIAN_POVRAY = "/usr/bin/povray"


# ============================================================================================
# Running povray

class RenderError(RuntimeError):
    pass


class Run:
    """Outcome of one process: exit status, output (stdout and stderr together unless
    separate=True, then .stdout and .stderr too), seconds, whether the time limit killed it."""

    def __init__(self, returncode, output, seconds, timed_out, stdout=None, stderr=None):
        self.returncode = returncode
        self.output = output
        self.seconds = seconds
        self.timed_out = timed_out
        self.stdout = stdout
        self.stderr = stderr


def run_process(cmd, cwd=None, timeout=60, env=None, separate=False, binary=False):
    """Runs cmd in its own process group and kills the whole group at the time limit, through
    the decoder package's one POV-Ray runner (plenoptic_lf.povray.run_povray). Output is decoded
    as UTF-8 (errors replaced) unless binary=True."""
    from plenoptic_lf.povray import run_povray as _run
    run = _run(cmd, cwd=cwd, timeout=timeout, env=env, separate=separate)
    if binary:
        return Run(run.returncode, run.output_bytes, run.seconds, run.timed_out, run.stdout_bytes, run.stderr_bytes)
    return Run(run.returncode, run.output, run.seconds, run.timed_out, run.stdout, run.stderr)


def run_povray(povray, scene, out, width, height, extra=(), timeout=60, cwd=None, options=("-D", "-P", "-GS", "-GR")):
    """Runs povray on the scene file `scene` writing `out` (`+I +O +W +H`, then `options`, then
    `extra`); kills the whole process group at the time limit. Returns a Run."""
    from plenoptic_lf.povray import povray_command
    cmd = povray_command(povray, scene, out, width, height, list(options) + list(extra))
    return run_process(cmd, cwd=cwd or os.path.dirname(os.path.abspath(out)), timeout=timeout)


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


def first_error(text, code):
    """The first error POV-Ray printed, on one line (the error line and the two after it)."""
    lines = [l.strip() for l in text.splitlines() if l.strip()]
    for i, l in enumerate(lines):
        if "error" in l.lower():
            return " | ".join(lines[i:i + 3])[:400]
    return ("exit %d: %s" % (code, lines[-1] if lines else "no output"))[:400]


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


def tail(text, n=15):
    return "\n".join("    | " + t for t in text.rstrip().splitlines()[-n:])


def require_debian_povray(path=DEBIAN_POVRAY):
    """Debian's packaged povray, the reference some tests compare with (an assertion when missing)."""
    assert os.path.exists(path), "Debian's povray (%s) is not installed: run tools/install-deps" % path
    return path


# ============================================================================================
# Scenes and renders

SCENE_HEADER = """#version 3.7;
global_settings { assumed_gamma 1.0 }
"""

# Command-line presets after +I +O +W +H (the options each family has always rendered with).
# LINEAR16: 16-bit PNG, linear (File_Gamma 1), no antialiasing, quiet; HALF_EXR: the same as
# half-float OpenEXR; GROUND_TRUTH: 16-bit linear PNG with the ini's other defaults.
LINEAR16 = ("-D", "-P", "-A", "-V", "-GR", "-GS", "+FN16", "File_Gamma=1.0")
HALF_EXR = ("-D", "-P", "-A", "-V", "-GR", "-GS", "+FE")
GROUND_TRUTH = ("-D", "-P", "+FN16", "File_Gamma=1.0")


def write_text(path, text):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)
    return path


def remove_outputs(work, name, ext="png"):
    """Removes <work>/<name>.<ext> and the files a plenoptic render writes beside it."""
    for suffix in ("." + ext, ".plenoptic.json", ".depth.exr"):
        p = os.path.join(work, name + suffix)
        if os.path.exists(p):
            os.remove(p)


def render(povray, work, name, scene, width, height, ext="png", extra=(), expect_failure=False,
           options=None, relative=False, timeout=300):
    """Writes `scene` (text) to <work>/<name>.pov and renders it to <work>/<name>.<ext> in <work>.

    options: the preset after +I +O +W +H (default LINEAR16 for PNG, HALF_EXR for EXR); both give
    values proportional to the traced radiance. relative: +I and +O name the files relative to
    <work> instead of by absolute path. Stale outputs (image, metadata, depth map) are removed
    first. Returns the path of the image, or (exit status, console text) when expect_failure is
    set (then nothing is required of the render). Raises RenderError when the render fails.
    """
    os.makedirs(work, exist_ok=True)
    pov = os.path.join(work, name + ".pov")
    out = os.path.join(work, name + "." + ext)
    write_text(pov, scene)
    remove_outputs(work, name, ext)
    if options is None:
        options = {"png": LINEAR16, "exr": HALF_EXR}[ext]
    from plenoptic_lf.povray import povray_command
    cmd = povray_command(povray, name + ".pov" if relative else pov, name + "." + ext if relative else out,
                         width, height, list(options) + list(extra))
    run = run_process(cmd, cwd=work, timeout=timeout)
    if expect_failure:
        return run.returncode, run.output
    animated = any(a.startswith("+KFF") for a in extra)  # frames are <name><number>.<ext>
    if run.timed_out or run.returncode != 0 or not (animated or os.path.exists(out)):
        raise RenderError("render of %s failed (exit %s%s): %s\n%s" %
                          (pov, run.returncode, ", time limit" if run.timed_out else "", " ".join(cmd),
                           run.output[-3000:]))
    return out


def render_ground_truth(povray, work, name, scene, width, height, extra=()):
    """A scene (SCENE_HEADER added) as <work>/<name>.png, 16-bit linear; the paths of the image,
    the metadata and the depth map."""
    png = render(povray, work, name, SCENE_HEADER + scene, width, height, extra=extra,
                 options=GROUND_TRUTH, relative=True)
    return png, os.path.join(work, name + ".plenoptic.json"), os.path.join(work, name + ".depth.exr")


# A textured 3-D scene in metres (one unit = 1 m = 1000 mm, the camera's default scale):
# a checkered floor, a marbled sphere, a striped box and a wall with a fine grid, at depths
# from 1.5 to 6 m in front of a camera at z = -3 looking along +z. No randomness (no area
# lights, no jitter, no radiosity), so every camera sees exactly the same surfaces.
TEXTURED_SCENE = """
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "colors.inc"
light_source { <-3, 6, -6> rgb 1.0 }
light_source { <4, 3, -5> rgb 0.35 shadowless }
background { rgb <0.45, 0.6, 0.85> }
plane { y, 0
  pigment { checker rgb <0.9, 0.85, 0.7> rgb <0.15, 0.2, 0.25> scale 0.25 }
  finish { diffuse 0.8 ambient 0.1 } }
sphere { <-0.45, 0.4, -1.2>, 0.4
  pigment { marble turbulence 0.8 color_map { [0 rgb <0.9, 0.2, 0.1>] [0.5 rgb <1, 0.9, 0.5>] [1 rgb <0.3, 0.05, 0.1>] } scale 0.15 }
  finish { specular 0.4 roughness 0.02 ambient 0.1 } }
box { <-0.25, 0, -0.25>, <0.25, 0.9, 0.25> rotate y*30 translate <0.55, 0, 0.2>
  pigment { gradient x color_map { [0 rgb <0.1, 0.3, 0.9>] [0.5 rgb <0.1, 0.3, 0.9>] [0.5 rgb 1] [1 rgb 1] } scale 0.08 }
  finish { ambient 0.1 } }
cylinder { <0, 0, 0>, <0, 1.4, 0>, 0.12 translate <-0.1, 0, 1.4>
  pigment { radial frequency 12 color_map { [0 rgb <0.1, 0.6, 0.2>] [0.5 rgb <0.1, 0.6, 0.2>] [0.5 rgb <0.9, 0.9, 0.2>] [1 rgb <0.9, 0.9, 0.2>] } }
  finish { ambient 0.1 } }
plane { -z, -3
  pigment { checker rgb <0.8, 0.8, 0.8> rgb <0.3, 0.25, 0.35> scale 0.1 }
  finish { ambient 0.15 diffuse 0.7 } }
"""

# The world of the robustness scenes; only the camera changes from case to case.
WORLD = """\
light_source { <-3, 5, -4> color rgb 1 }
light_source { <4, 3, -2> color rgb 0.3 shadowless }
sky_sphere { pigment { gradient y color_map { [0 rgb <0.75, 0.85, 1>] [1 rgb <0.3, 0.45, 0.8>] } } }
plane { y, 0 pigment { checker color rgb 0.9 color rgb 0.2 scale 0.25 } }
sphere { <0, 0.3, 0>, 0.3 pigment { color rgb <0.9, 0.3, 0.2> } finish { specular 0.4 } }
box { <-0.9, 0, 0.8>, <-0.5, 0.5, 1.0> pigment { color rgb <0.2, 0.5, 0.9> } }
"""

WORLD_HEADER = "// SPDX-License-Identifier: AGPL-3.0-or-later\n#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n"


def scene_text(camera_block):
    """A whole robustness scene: header, the given camera block (text, verbatim), WORLD."""
    return WORLD_HEADER + camera_block.rstrip("\n") + "\n" + WORLD


def write_scene(path, camera_block):
    return write_text(path, scene_text(camera_block))


# ============================================================================================
# Images

def read_pixels(path, native=False):
    """The pixels (H, W, channels) of any image OpenImageIO reads, as it gives them (float32;
    PNG as 0..1; with native, in the file's own sample type), through the decoder package's one
    image reader (OpenImageIO's ImageInput, which reads the file anew each time). Raises
    RenderError when the file cannot be read."""
    from plenoptic_lf.images import ImageReadError, read_image
    try:
        return read_image(path, native=native)
    except ImageReadError as e:
        raise RenderError(str(e)) from None


def load(path):
    """Image as float64 array [row, column, channel] (values as stored, 0..1 for PNG)."""
    return np.asarray(read_pixels(path), dtype=np.float64)


def read_linear(png):
    """16-bit linear PNG -> float64 (H, W, 3) in [0, 1]."""
    return load(png)[:, :, :3]


def save_png(path, array):
    """Writes a float image (H, W[, C]) in 0..1 as an 8-bit PNG, for a person to look at."""
    import OpenImageIO as oiio
    a = np.clip(np.asarray(array, dtype=np.float64), 0, 1)
    if a.ndim == 2:
        a = a[:, :, None]
    spec = oiio.ImageSpec(a.shape[1], a.shape[0], a.shape[2], oiio.UINT8)
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec):
        raise RenderError("cannot write %s: %s" % (path, oiio.geterror()))
    out.write_image(np.ascontiguousarray((a * 255 + 0.5).astype(np.uint8)))
    out.close()


def idiff_command():
    exe = shutil.which("idiff")
    assert exe, "OpenImageIO's idiff is not installed (Debian: openimageio-tools; run tools/install-deps)"
    return exe


def idiff(ref, new, args=(), diff_out=None):
    """OpenImageIO's idiff on two images with the given threshold arguments (and, with diff_out,
    `-abs -scale 16 -o diff_out`). Returns (exit code, idiff's report). Exit codes: 0 identical
    within -fail, 1 warning only, 2 failure, 3 size mismatch, 4 file error."""
    cmd = [idiff_command()] + list(args)
    if diff_out:
        cmd += ["-abs", "-scale", "16", "-o", diff_out]
    res = subprocess.run(cmd + [ref, new], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    return res.returncode, res.stdout.decode(errors="replace").strip()


# ============================================================================================
# Metadata and JSON, strictly

# The decoder package's one metadata reader (python/plenoptic_lf/metadata.py) does the reading:
# strict JSON and the schema through jsonschema. Its messages are the tools' own.
from plenoptic_lf.errors import MetadataError  # noqa: E402
from plenoptic_lf import metadata as _metadata  # noqa: E402


def schema_errors(doc):
    """The schema's complaints about a document, as "field: message" strings (empty: valid)."""
    return _metadata.schema_problems(doc)


def validate(doc, where="metadata"):
    """Raises MetadataError when `doc` does not match docs/metadata.schema.json."""
    try:
        _metadata.check_schema(doc)
    except MetadataError as e:
        raise MetadataError("%s %s" % (where, e)) from None


def parse_json_strict(data, where="metadata"):
    """The document in `data` (bytes or str), read strictly (UTF-8 only, no lone surrogate, no
    duplicate key, no NaN or Infinity); MetadataError naming `where`."""
    try:
        doc = _metadata.parse_json(data)
        _metadata.check_finite(doc)
    except MetadataError as e:
        raise MetadataError("%s: %s" % (where, e)) from None
    return doc


def load_metadata(path, check_schema=True):
    """The metadata file at `path`, read strictly and (by default) validated against the schema."""
    try:
        return _metadata.read_document(path, schema=check_schema)
    except MetadataError as e:
        raise MetadataError("%s: %s" % (path, e)) from None


def metadata_of(image_path):
    """The render's metadata (<stem>.plenoptic.json beside the image), strict and schema-checked."""
    return load_metadata(os.path.splitext(image_path)[0] + ".plenoptic.json")


def read_json(path):
    """A JSON file; a render's metadata (*.plenoptic.json) strictly and schema-checked."""
    if path.endswith(".plenoptic.json"):
        return load_metadata(path)
    with open(path) as f:
        return json.load(f)


# ============================================================================================
# The optics of docs/specification.md, written out again

SQRT3 = math.sqrt(3.0)


def image_distance(F, z):
    """Thin lens: where an object at distance z (same unit as F, z > F) is imaged behind the
    lens (1/F = 1/z + 1/D)."""
    return z * F / (z - F)


def thin_lens_D(F, z_mm):
    """Image distance of a thin lens focused at z, as 1 / (1/F - 1/z)."""
    return 1.0 / (1.0 / F - 1.0 / z_mm)


def rotation_xyz(deg):
    """Rotate about x, then y, then z (POV-Ray's order), degrees; column-vector matrix."""
    ax, ay, az = [math.radians(a) for a in deg]
    cx, sx = math.cos(ax), math.sin(ax)
    cy, sy = math.cos(ay), math.sin(ay)
    cz, sz = math.cos(az), math.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def rot_z(degrees):
    a = math.radians(degrees)
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def lattice_point(grid, pitch, k, l):
    """Lens centre (x, y, 0) in the array's own plane (docs/specification.md, section 2), row form."""
    if grid == "hexagonal":
        return np.array([(k + (l % 2) / 2.0) * pitch, l * pitch * SQRT3 / 2.0, 0.0])
    return np.array([k * pitch, l * pitch, 0.0])


def lens_centre_local(grid, pitch, k, l):
    """Lens (k, l) in row form, in the array's own plane, (..., 2); k and l may be arrays."""
    k = np.asarray(k, float)
    l = np.asarray(l, float)
    if grid == "hexagonal":
        return np.stack([(k + np.mod(l, 2) / 2.0) * pitch, l * pitch * math.sqrt(3) / 2.0], axis=-1)
    return np.stack([k * pitch, l * pitch], axis=-1)


def posed_lens_centre(grid, pitch, k, l, rotate, translate, D):
    """Optics-frame centre of lens (k, l): rotate, translate, then place at z = -D."""
    q = rotation_xyz(rotate) @ lattice_point(grid, pitch, k, l)
    return q + np.array(translate, dtype=float) + np.array([0.0, 0.0, -D])


def nearest_lens_local(grid, pitch, xy):
    """Row-form index of the lens whose centre is nearest each point (array-local mm), by brute
    force over the candidates around it; also the gap between the best and second-best squared
    distance (small: the point is near a cell border). xy: (..., 2)."""
    xy = np.asarray(xy, float)
    row = pitch * (math.sqrt(3) / 2.0 if grid == "hexagonal" else 1.0)
    l0 = np.floor(xy[..., 1] / row)
    best_d = np.full(xy.shape[:-1], np.inf)
    second_d = np.full(xy.shape[:-1], np.inf)
    best_k = np.zeros(xy.shape[:-1])
    best_l = np.zeros(xy.shape[:-1])
    for dl in (-1, 0, 1, 2):
        l = l0 + dl
        shift = np.mod(l, 2) / 2.0 if grid == "hexagonal" else 0.0
        k0 = np.floor(xy[..., 0] / pitch - shift)
        for dk in (-1, 0, 1, 2):
            k = k0 + dk
            c = lens_centre_local(grid, pitch, k, l)
            d = ((xy - c) ** 2).sum(axis=-1)
            better = d < best_d
            second_d = np.where(better, best_d, np.minimum(second_d, d))
            best_k = np.where(better, k, best_k)
            best_l = np.where(better, l, best_l)
            best_d = np.where(better, d, best_d)
    return best_k, best_l, second_d - best_d


def sensor_point(i, j, W, H, sx, sy, ox=0.0, oy=0.0):
    """Sensor position (mm, optics frame) of the centre of pixel (column i, row j):
    docs/specification.md, section 2, with (i + 0.5) the centre of a pixel spanning [i, i + 1)."""
    return -((np.asarray(i, float) + 0.5) - W / 2.0) * sx + ox, ((np.asarray(j, float) + 0.5) - H / 2.0) * sy + oy


def sensor_to_pixel(x, y, W, H, sx, sy, ox=0.0, oy=0.0):
    """Sensor point (optics frame, mm) -> continuous pixel coordinates with the centre of pixel
    (i, j) at (i, j): the inverse of sensor_point, the metadata's convention."""
    return W / 2.0 - 0.5 - (np.asarray(x) - ox) / sx, H / 2.0 - 0.5 + (np.asarray(y) - oy) / sy


# ============================================================================================
# Image measurements (scipy.ndimage)

FOUR_CONNECTED = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], dtype=bool)
EIGHT_CONNECTED = np.ones((3, 3), dtype=bool)


def label_components(mask, connectivity=4):
    """Connected components of a boolean mask (4- or 8-connected): (labels, count), labels
    1..count in raster order of each component's first pixel."""
    from scipy import ndimage
    structure = FOUR_CONNECTED if connectivity == 4 else EIGHT_CONNECTED
    labels, count = ndimage.label(np.asarray(mask, dtype=bool), structure=structure)
    return labels, int(count)


def dilate(mask, radius):
    """Binary dilation by a (2 radius + 1)^2 square (pixels beyond the border count as unset)."""
    from scipy import ndimage
    size = 2 * radius + 1
    return ndimage.binary_dilation(np.asarray(mask, dtype=bool), structure=np.ones((size, size), dtype=bool))


def component_centroids(weight, labels, count):
    """Weighted centroid (u, v) (pixel-centre convention), weight sum, bounding box and pixel
    count of every component whose weight sum is positive."""
    from scipy import ndimage
    if count == 0:
        return []
    weight = np.asarray(weight, dtype=np.float64)
    index = np.arange(1, count + 1)
    sums = ndimage.sum_labels(weight, labels, index)
    vv, uu = np.mgrid[0:weight.shape[0], 0:weight.shape[1]]
    su = ndimage.sum_labels(uu * weight, labels, index)
    sv = ndimage.sum_labels(vv * weight, labels, index)
    pixels = ndimage.sum_labels(np.ones_like(weight), labels, index)
    boxes = ndimage.find_objects(labels)
    out = []
    for c in range(count):
        if not sums[c] > 0:
            continue
        rows, cols = boxes[c]
        out.append({"u": float(su[c] / sums[c]), "v": float(sv[c] / sums[c]), "weight": float(sums[c]),
                    "umin": cols.start, "umax": cols.stop - 1, "vmin": rows.start, "vmax": rows.stop - 1,
                    "pixels": int(pixels[c])})
    return out


def blobs(image, threshold):
    """8-connected components of pixels brighter than threshold in a grey image, in raster order
    of their first pixel: centroid (u, v) weighted by brightness (pixel (i, j) centre at (i, j)),
    flux (sum), count, bbox (umin, vmin, umax, vmax)."""
    labels, count = label_components(image > threshold, connectivity=8)
    return [{"u": c["u"], "v": c["v"], "flux": c["weight"], "count": c["pixels"],
             "bbox": (c["umin"], c["vmin"], c["umax"], c["vmax"])}
            for c in component_centroids(image, labels, count)]


def shift_rows(image, shift):
    """image (T, S) sampled at s - shift along its rows, linear interpolation; NaN outside."""
    S = image.shape[1]
    x = np.arange(S) - shift
    x0 = np.floor(x).astype(int)
    f = x - x0
    ok = (x0 >= 0) & (x0 + 1 <= S - 1)
    out = np.full(image.shape, np.nan)
    out[:, ok] = image[:, x0[ok]] * (1 - f[ok]) + image[:, x0[ok] + 1] * f[ok]
    return out


def box_blur(img, k):
    """Mean over k x k neighbourhoods, 'valid' region only (shape reduced by k - 1), any number
    of channels."""
    from scipy import ndimage
    a = np.asarray(img, dtype=np.float64)
    size = (k, k) + (1,) * (a.ndim - 2)
    full = ndimage.uniform_filter(a, size=size, mode="constant")
    h = k // 2  # uniform_filter centres an even window at k // 2
    return full[h:h + a.shape[0] - k + 1, h:h + a.shape[1] - k + 1]


# ============================================================================================
# The tools: plenoptic-decode (in the tree), plenoptic-project

def decoder(tools):
    """The command that runs the in-tree plenoptic-decode launcher of the tools/ folder."""
    return [sys.executable, os.path.join(tools, "plenoptic-decode")]


def run_project(project, metadata, points, fraction=False):
    """plenoptic-project on world points: list of (point index, k, l, u, v), and with fraction=True
    (--fraction) also the fraction of the light, 1 from a tool without --fraction."""
    coords = ["%.17g" % c for p in points for c in p]
    with_fraction = False
    if fraction:
        run = subprocess.run([project, "--fraction", metadata] + coords, capture_output=True, text=True)
        with_fraction = run.returncode == 0
    if not with_fraction:
        run = subprocess.run([project, metadata] + coords, capture_output=True, text=True)
    assert run.returncode == 0, "plenoptic-project exited %d: %s" % (run.returncode, run.stderr.strip())
    hits = []
    for line in run.stdout.splitlines():
        if not line.strip():
            continue
        f = line.split()
        hit = (int(f[0]), int(f[1]), int(f[2]), float(f[3]), float(f[4]))
        if fraction:
            hit += (float(f[5]) if with_fraction else 1.0,)
        hits.append(hit)
    return hits


# ============================================================================================
# The golden scenes (tests/golden/scenes.json: one row per scene, thresholds over defaults)

GOLDEN_DIR = os.path.join(TESTS_DIR, "golden")
GOLDEN_SCENES_DIR = os.path.join(GOLDEN_DIR, "scenes")
GOLDEN_TABLE = os.path.join(GOLDEN_DIR, "scenes.json")


def golden_table(path=GOLDEN_TABLE):
    with open(path) as f:
        return json.load(f)


def golden_settings(table, name):
    """The scene's row merged over the defaults (one level deep for the threshold blocks)."""
    if name not in table["scenes"]:
        raise KeyError("scene '%s' is not in %s" % (name, GOLDEN_TABLE))
    row = table["scenes"][name]
    out = {}
    for k, v in table["defaults"].items():
        out[k] = dict(v) if isinstance(v, dict) else v
    for k, v in row.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k].update(v)
        else:
            out[k] = v
    return out


def render_golden(povray, name, s, out_dir, extra=()):
    """Renders golden/scenes/<name>.pov into out_dir/<name>.png (8-bit unless extra says
    otherwise) with the row's size and options; returns the povray output text."""
    os.makedirs(out_dir, exist_ok=True)
    png = os.path.join(out_dir, name + ".png")
    remove_outputs(out_dir, name)
    from plenoptic_lf.povray import povray_command
    cmd = povray_command(povray, os.path.join(GOLDEN_SCENES_DIR, name + ".pov"), png, s["width"], s["height"],
                         ["-D", "-P", "+FN8", "-GS", "-GR", "+L" + GOLDEN_SCENES_DIR] + list(s.get("options", []))
                         + list(extra))
    run = run_process(cmd, cwd=out_dir, timeout=600)
    if run.timed_out or run.returncode != 0 or not os.path.exists(png):
        raise RenderError("render of %s failed (exit %s%s):\n  %s\n%s"
                          % (name, run.returncode, ", time limit" if run.timed_out else "", " ".join(cmd),
                             run.output[-3000:]))
    return run.output


# Four self-lit coloured quadrants 6 cm wide at z = 0 on a dark background (a chart at the focus
# distance of the decoder tests: flat microimages inside each quadrant, edges between them).
QUADRANT_CHART = """\
#version 3.7;
global_settings { assumed_gamma 1.0 }
background { rgb 0.05 }
#declare Lit = finish { emission 1 diffuse 0 ambient 0 }
box { <-0.03, 0, 0>, <0, 0.03, 0.001> pigment { rgb <0.8, 0.25, 0.2> } finish { Lit } }
box { <0, 0, 0>, <0.03, 0.03, 0.001> pigment { rgb <0.25, 0.7, 0.3> } finish { Lit } }
box { <-0.03, -0.03, 0>, <0, 0, 0.001> pigment { rgb <0.2, 0.3, 0.8> } finish { Lit } }
box { <0, -0.03, 0>, <0.03, 0, 0.001> pigment { rgb <0.85, 0.8, 0.3> } finish { Lit } }
"""


def white_image_values(white_path):
    """A linear white image's values (H, W, C): stored / 65535 times the scale its metadata entry
    gives, and that scale. The metadata is the render's, found from the white image's name."""
    image = re.sub(r"\.white(\.f[0-9.]+)?\.png$", ".png", white_path)
    entry = [w for w in metadata_of(image)["white_images"] if w["file"] == os.path.basename(white_path)][0]
    return load(white_path) * entry["scale"], entry["scale"]


def white_image_step(scale):
    """The largest difference between a white image of this scale and a 16-bit render of the same
    values: both quantisations, half a step each."""
    return (scale + 1) / 2.0 / 65535 + 1e-12
