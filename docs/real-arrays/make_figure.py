#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""The figure of docs/camera.md, "Real microlens arrays": the same white-image crop through an
ideal, a jittered, a refracting and a masked array (Lytro-class: hexagonal 20 um microlenses at
f/3.5 behind a 50 mm f/3.5 thin lens, 1.4 um pixels).

    /usr/bin/python3 docs/real-arrays/make_figure.py build/povray

renders the four crops (a few seconds each) and writes docs/real-arrays/microlens_arrays.png."""
import os
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image, ImageDraw

HERE = os.path.dirname(os.path.abspath(__file__))
W, H, ZOOM = 112, 84, 4
BASE = "hexagonal pitch 0.02 focal_length 0.07 distance 0.07"
PANELS = [
    ("ideal", BASE),
    ("jittered (position 0.4 um, focal 2 %, tilt 1 deg)",
     BASE + " errors { position 0.0004 focal_length 0.02 rotation 1 seed 4 }"),
    ("refracting (R 0.032 mm, n 1.46, caps towards the scene)",
     "hexagonal pitch 0.02 lens { surface { radius 0.032 } thickness 0.004 ior 1.46 substrate 0.01 }"
     " distance 0.06"),
    ("masked (fill factor 0.7)", BASE + " fill_factor 0.7 mask on"),
]


def render(povray, work, name, array):
    scene = os.path.join(work, name + ".pov")
    with open(scene, "w") as f:
        f.write("#version 3.7;\nglobal_settings { assumed_gamma 1 }\nbackground { rgb 1 }\n"
                "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n"
                "  main_lens { thin_lens focal_length 50 f_number 3.5 focus_distance 2 }\n"
                "  microlens_array { %s }\n  sensor { pixel_size 0.0014 }\n  samples 64\n}\n" % array)
    out = os.path.join(work, name + ".png")
    subprocess.run([povray, "+I" + scene, "+O" + out, "+W%d" % W, "+H%d" % H, "-D", "-P", "-GA", "+FN16",
                    "File_Gamma=1.0"], check=True, cwd=work, capture_output=True)
    return np.asarray(Image.open(out).convert("L"))


def main():
    povray = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "build/povray")
    work = tempfile.mkdtemp(prefix="array-figure-")
    tiles = []
    for i, (label, array) in enumerate(PANELS):
        image = Image.fromarray(render(povray, work, "panel%d" % i, array)).resize((W * ZOOM, H * ZOOM), Image.NEAREST)
        tile = Image.new("L", (W * ZOOM, H * ZOOM + 18), 255)
        tile.paste(image, (0, 18))
        ImageDraw.Draw(tile).text((4, 3), label, fill=0)
        tiles.append(tile)
    sheet = Image.new("L", (2 * W * ZOOM + 6, 2 * (H * ZOOM + 18) + 6), 255)
    for i, tile in enumerate(tiles):
        sheet.paste(tile, ((i % 2) * (W * ZOOM + 6), (i // 2) * (H * ZOOM + 24)))
    path = os.path.join(HERE, "microlens_arrays.png")
    sheet.save(path)
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
