#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Determinism: one scene of tests/golden/scenes.json, rendered with one render thread, with
two, and with two threads and small render blocks (another split of the work), must give
byte-identical files: the 16-bit PNG (every chunk but the two that hold the time of the
render), the metadata JSON and the depth EXR when there is one.

The specification (docs/specification.md, section 3) asks for the same image whatever the
thread count; POV-Ray's own focal blur has the same property.
"""
import argparse
import hashlib
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import golden  # noqa: E402  (render() and the scene table)

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


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--povray", required=True)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()

    s = golden.settings(golden.load_table(), args.scene)
    # Thread options of the golden row are replaced by each variant's.
    s["options"] = [o for o in s.get("options", []) if not o.upper().startswith(("+WT", "+BS"))]
    files = {}
    for label, extra in VARIANTS:
        out = os.path.join(os.path.abspath(args.work), args.scene, label)
        try:
            golden.render(args.povray, args.scene, s, out, extra=["+FN16"] + extra)
        except RuntimeError as e:
            print("FAIL %s: %s" % (args.scene, e))
            return 1
        files[label] = {}
        for suffix in (".png", ".plenoptic.json", ".depth.exr"):
            p = os.path.join(out, args.scene + suffix)
            if os.path.exists(p):
                files[label][suffix] = p

    failed = False
    base_label = VARIANTS[0][0]
    base = files[base_label]
    for label, _ in VARIANTS[1:]:
        other = files[label]
        if sorted(base) != sorted(other):
            print("FAIL %s: %s wrote %s, %s wrote %s" % (args.scene, base_label, sorted(base), label, sorted(other)))
            failed = True
            continue
        for suffix in sorted(base):
            a, b = base[suffix], other[suffix]
            if digest(a) == digest(b):
                print("same bytes: %s %s vs %s (%d bytes)" % (suffix, base_label, label, os.path.getsize(a)))
            else:
                extra = pixel_report(a, b) if suffix == ".png" else ""
                print("FAIL %s: %s differs between %s and %s: %s vs %s %s"
                      % (args.scene, suffix, base_label, label, a, b, extra))
                failed = True
    if failed:
        return 1
    print("ok   %s: byte-identical with %s" % (args.scene, ", ".join(l for l, _ in VARIANTS)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
