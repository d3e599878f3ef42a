# SPDX-License-Identifier: AGPL-3.0-or-later
"""Determinism: one scene of tests/golden/scenes.json, rendered with one render thread, with
two, and with two threads and small render blocks (another split of the work), must give
byte-identical files: the 16-bit PNG (every chunk but the two that hold the time of the
render), the metadata JSON and the depth EXR when there is one.

The specification (docs/specification.md, section 3) asks for the same image whatever the
thread count; POV-Ray's own focal blur has the same property.
"""
import hashlib
import os
import struct

import pytest

import plenoptic_testing as pt

# The scenes ctest runs as determinism_<scene> (tests/golden/CMakeLists.txt).
SCENES = ["plenoptic1_hex", "adaptive", "overlap_hex", "thin_none", "tilted_array", "depth_outputs"]

VARIANTS = [
    ("wt1", ["+WT1"]),
    ("wt2", ["+WT2"]),
    ("wt2_bs8", ["+WT2", "+BS8"]),
]


# Chunks in which POV-Ray writes the time of the render (tIME, and the "Render Date" comment).
PNG_TIME_CHUNKS = (b"tIME", b"tEXt", b"zTXt", b"iTXt")


def digest(path):
    """SHA-256 of the file; of a PNG, of every chunk but the time stamps (the pixels, the
    header, gamma: all bytes that depend on the render)."""
    with open(path, "rb") as f:
        data = f.read()
    if not path.endswith(".png"):
        return hashlib.sha256(data).hexdigest()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise RuntimeError("%s is not a PNG file" % path)
    h = hashlib.sha256(data[:8])
    i = 8
    while i + 12 <= len(data):
        n = struct.unpack(">I", data[i:i + 4])[0]
        kind = data[i + 4:i + 8]
        if kind not in PNG_TIME_CHUNKS:
            h.update(data[i:i + 12 + n])
        i += 12 + n
    return h.hexdigest()


def pixel_report(a, b):
    """Where two PNGs differ, for the failure message."""
    try:
        import numpy as np
        from PIL import Image
        x = np.asarray(Image.open(a)).astype(np.int64)
        y = np.asarray(Image.open(b)).astype(np.int64)
        if x.shape != y.shape:
            return "shapes %s vs %s" % (x.shape, y.shape)
        d = np.abs(x - y)
        if d.ndim == 3:
            d = d.max(axis=2)
        n = int(np.count_nonzero(d))
        if n == 0:
            return "same pixels, different file bytes"
        ys, xs = np.nonzero(d)
        return "%d pixel(s) differ, largest by %d/65535, first at (x %d, y %d)" % (n, int(d.max()), xs[0], ys[0])
    except Exception as e:  # only a diagnostic
        return "(cannot compare pixels: %s)" % e


@pytest.mark.parametrize("scene", SCENES)
def test_determinism(args, scene):
    s = pt.golden_settings(pt.golden_table(), scene)
    # Thread options of the golden row are replaced by each variant's.
    s["options"] = [o for o in s.get("options", []) if not o.upper().startswith(("+WT", "+BS"))]
    files = {}
    for label, extra in VARIANTS:
        out = os.path.join(args.work, scene, label)
        pt.render_golden(args.povray, scene, s, out, extra=["+FN16"] + extra)
        files[label] = {}
        for suffix in (".png", ".plenoptic.json", ".depth.exr"):
            p = os.path.join(out, scene + suffix)
            if os.path.exists(p):
                files[label][suffix] = p

    failures = []
    base_label = VARIANTS[0][0]
    base = files[base_label]
    for label, _ in VARIANTS[1:]:
        other = files[label]
        if sorted(base) != sorted(other):
            failures.append("%s wrote %s, %s wrote %s" % (base_label, sorted(base), label, sorted(other)))
            continue
        for suffix in sorted(base):
            a, b = base[suffix], other[suffix]
            if digest(a) == digest(b):
                print("same bytes: %s %s vs %s (%d bytes)" % (suffix, base_label, label, os.path.getsize(a)))
            else:
                extra = pixel_report(a, b) if suffix == ".png" else ""
                failures.append("%s differs between %s and %s: %s vs %s %s" % (suffix, base_label, label, a, b, extra))
    assert not failures, "%s: %s" % (scene, "\n".join(failures))
