#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Render scenes of POV-Ray's own distribution with our build and with Debian's
packaged povray, and compare the images with OpenImageIO's idiff.

This proves the build is faithful to Debian's before our camera changes anything.
"""
import argparse
import os
import shutil
import subprocess
import sys

# Small, quick scenes that exercise different parts of the renderer
# (CSG, textures, normals, media, focal blur, isosurfaces, radiosity-free lighting).
DEFAULT_SCENES = [
    "advanced/biscuit.pov",
    "advanced/woodbox.pov",
    "advanced/chess2.pov",
    "advanced/optics.pov",
    "advanced/quilt1.pov",
    "camera/focalblur.pov",
    "camera/fisheye.pov",
    "advanced/isocacti.pov",
]

# idiff thresholds: builds with different compilers/flags may differ by rounding in a
# few pixels; anything beyond 1/255 in more than 0.5% of pixels, or any pixel off by
# more than 0.1, is a real difference.
IDIFF_ARGS = ["-fail", "0.004", "-failpercent", "0.5", "-hardfail", "0.1",
              "-warn", "0.004", "-warnpercent", "0.01"]


# One render thread: some stock scenes (quilt1's quilted normal) differ from run to run
# with 2 threads even in Debian's own binary.
def render(povray, scene, out_png, width, height, extra):
    scene_dir = os.path.dirname(scene)
    cmd = [povray, "+I" + scene, "+O" + out_png, "+W%d" % width, "+H%d" % height,
           "-D", "-P", "+FN8", "+L" + scene_dir, "-GS", "-GR", "+WT1"] + extra
    res = subprocess.run(cmd, cwd=os.path.dirname(out_png), stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, timeout=600)
    if res.returncode != 0 or not os.path.exists(out_png):
        tail = res.stdout.decode(errors="replace")[-2000:]
        raise RuntimeError("%s failed on %s (exit %d):\n%s" % (povray, scene, res.returncode, tail))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--povray", required=True, help="our build's povray binary")
    ap.add_argument("--reference", default="/usr/bin/povray", help="Debian's packaged povray")
    ap.add_argument("--scenes-dir", required=True, help="distribution/scenes of the unpacked source")
    ap.add_argument("--out", required=True, help="work directory")
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("scenes", nargs="*", default=DEFAULT_SCENES)
    args = ap.parse_args()

    if not os.path.exists(args.reference):
        print("FAIL: Debian's povray (%s) is not installed: run tools/install-deps" % args.reference)
        return 1
    idiff = shutil.which("idiff")
    if not idiff:
        print("FAIL: OpenImageIO's idiff is not installed: run tools/install-deps")
        return 1
    os.makedirs(args.out, exist_ok=True)

    passed = failed = 0
    for rel in args.scenes:
        scene = os.path.join(args.scenes_dir, rel)
        stem = rel.replace("/", "_").replace(".pov", "")
        ours = os.path.join(args.out, stem + ".ours.png")
        ref = os.path.join(args.out, stem + ".debian.png")
        for f in (ours, ref):
            if os.path.exists(f):
                os.remove(f)
        try:
            render(args.povray, scene, ours, args.width, args.height, [])
            render(args.reference, scene, ref, args.width, args.height, [])
        except (RuntimeError, subprocess.TimeoutExpired) as e:
            print("FAIL %s: %s" % (rel, e))
            failed += 1
            continue
        diff_png = os.path.join(args.out, stem + ".diff.png")
        res = subprocess.run([idiff] + IDIFF_ARGS + ["-abs", "-scale", "16", "-o", diff_png, ref, ours],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        text = res.stdout.decode(errors="replace")
        if res.returncode in (0, 1):  # 0 identical, 1 within warning
            print("ok   %s (idiff exit %d)" % (rel, res.returncode))
            passed += 1
            if os.path.exists(diff_png):
                os.remove(diff_png)
        else:
            print("FAIL %s: idiff exit %d; diff image %s\n%s" % (rel, res.returncode, diff_png, text))
            failed += 1
    print("%d passed, %d failed" % (passed, failed))
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
