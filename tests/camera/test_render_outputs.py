# SPDX-License-Identifier: AGPL-3.0-or-later
"""What a plenoptic render prints and writes beside its image:

1. `+O-` sends the image to standard output: no `stdout.plenoptic.json` appears, a message says
   why, and standard output holds the PNG.
2. An output name of 244 characters (the longest whose `.plenoptic.json` name still fits the
   file system's 255) gets its metadata and depth map.
3. The render statistics count the camera rays actually traced: a bare pinhole array passes
   every sample, so "Samples" is W x H x samples exactly.
4. A `#version 3.1` scene says that the camera needs 3.5 or later.
"""
import os
import re

import plenoptic_testing as pt

SCENE = """#version %s;
global_settings { assumed_gamma 1.0 }
light_source { <-3, 6, -4> rgb 1 }
plane { y, 0 pigment { checker rgb 0.2 rgb 0.9 scale 0.25 } }
camera {
  plenoptic
  location <0, 0.5, -2> look_at <0, 0.3, 0>
  microlens_array { rectangular pitch 0.1 pinhole distance 0.4 }
  sensor { pixel_size 0.01 }
  samples 4
  depth_map
}
"""


def povray(args, work, scene_name, scene, extra):
    path = pt.write_text(os.path.join(work, scene_name), scene)
    return pt.run_process([args.povray, "+I" + path, "+W40", "+H30", "-D", "-P", "-GR", "+FN8"] + extra,
                          cwd=work, timeout=120, separate=True, binary=True)


def test_render_outputs(args):
    os.makedirs(args.work, exist_ok=True)

    # 1. +O-
    for stale in os.listdir(args.work):
        os.remove(os.path.join(args.work, stale))
    res = povray(args, args.work, "piped.pov", SCENE % "3.7", ["+O-"])
    err = " ".join(res.stderr.decode(errors="replace").split())
    assert (res.returncode == 0 and res.stdout[:8] == b"\x89PNG\r\n\x1a\n"), "+O- writes a PNG to stdout" + ": " + ("exit %d, stdout starts %r" % (res.returncode, res.stdout[:8]))
    strays = [n for n in os.listdir(args.work) if n.startswith("stdout")]
    assert not strays, "+O- leaves no stdout.* file" + ": " + ("files: %s" % strays)
    assert "standard output (+O-)" in err, "+O- says why there is no metadata" + ": " + (err[max(0, err.find("standard output") - 60):][:180])

    # 2. A long output name.
    stem = "n" * 240
    res = povray(args, args.work, "long.pov", SCENE % "3.7", ["+O" + stem + ".png"])
    names = set(os.listdir(args.work))
    assert (res.returncode == 0 and stem + ".plenoptic.json" in names and stem + ".depth.exr" in names), ("a 244-character output name gets its metadata and depth map" + ": " + ("exit %d, metadata %s, depth %s" % (res.returncode, stem + ".plenoptic.json" in names,
                                                     stem + ".depth.exr" in names)))
    leftovers = [n for n in names if n.startswith(".plenoptic-")]
    assert not leftovers, "no temporary file is left" + ": " + ("%s" % leftovers)

    # 3. Samples in the statistics.
    res = povray(args, args.work, "stats.pov", SCENE % "3.7", ["+Ostats.png"])
    out = res.stdout.decode(errors="replace") + res.stderr.decode(errors="replace")
    m = re.search(r"Pixels:\s+(\d+)\s+Samples:\s+(\d+)", out)
    expected = 40 * 30 * 4
    assert (m is not None and int(m.group(1)) == 1200 and int(m.group(2)) == expected), ("statistics count the rays traced" + ": " + ("%s (expected Pixels 1200, Samples %d)"
                 % (m.group(0) if m else "no statistics line", expected)))

    # 4. #version 3.1
    res = povray(args, args.work, "old.pov", SCENE % "3.1", ["+Oold.png"])
    err = " ".join((res.stdout + res.stderr).decode(errors="replace").split())
    assert (res.returncode != 0 and "needs #version 3.5 or later" in err and "3.1" in err), "#version 3.1 names the version the camera needs" + ": " + (err[err.find("Parse Error"):][:160])

