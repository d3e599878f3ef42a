#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""The figure of docs/export/raytrix.md: a multi-focus Galilean render (its array turned 7 degrees)
with the lenses its RayCalibData XML places, as PlenopticToolbox 2.0 reads it, drawn over it: a
circle of radius diameter/2 - lens_border per lens, coloured by the XML's lens type, the centre
lens (the XML's offset from the picture's centre) marked; beside it the disparity image
<stem>_disp.png (1/v, stretched from its smallest to its largest value; black: none) of the
plane, turned 55 degrees about y so that its virtual depth varies across the picture.

    /usr/bin/python3 docs/export/make_raytrix_figure.py build/povray

renders the scene (a few seconds), exports it with tools/plenoptic-export and writes
docs/export/raytrix_lattice.png."""
import math
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np
from PIL import Image, ImageDraw

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
W, H = 240, 180
SCENE = """#version 3.7;
global_settings { assumed_gamma 1.0 }
#declare Tex = texture { pigment { checker rgb <0.9, 0.85, 0.5> rgb <0.1, 0.2, 0.5> scale 0.0007 rotate z*20 }
  finish { emission 1 diffuse 0 } }
camera { plenoptic location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length 49.885 f_number 4 distance 56.86 }
  microlens_array { hexagonal pitch 0.12744 focal_lengths <0.58267, 0.52402, 0.56057> distance 0.33713 rotate <0, 0, 7> }
  sensor { pixel_size 0.0055 }
  samples 16 depth_map }
plane { z, 0 texture { Tex } rotate y*55 translate z*0.37 }
"""
COLOURS = [(230, 60, 60), (60, 200, 80), (70, 120, 255)]
SCALE = 3


def srgb(x):
    x = np.clip(x, 0, 1)
    return (np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055) * 255 + 0.5).astype(np.uint8)


def main():
    povray = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "povray")
    sys.path.insert(0, os.path.join(ROOT, "python"))
    from plenoptic_lf.images import read_image
    with tempfile.TemporaryDirectory() as work:
        with open(os.path.join(work, "scene.pov"), "w") as f:
            f.write(SCENE)
        subprocess.run([povray, "+Iscene.pov", "+Oscene.png", "+W%d" % W, "+H%d" % H, "-D", "-P", "+FN16",
                        "File_Gamma=1.0"], cwd=work, check=True, capture_output=True)
        subprocess.run([sys.executable, os.path.join(ROOT, "tools", "plenoptic-export"), "scene.png", "--to", "raytrix",
                        "out", "-q"], cwd=work, check=True)
        picture = read_image(os.path.join(work, "scene.png"))[..., :3]
        disparity = read_image(os.path.join(work, "out", "scene_disp.png"))[..., 0]
        root = ET.parse(os.path.join(work, "out", "scene.xml")).getroot()
    number = lambda path: float(root.find(path).text)  # noqa: E731
    diameter, rotation, border = number("diameter"), number("rotation"), number("lens_border")
    ox, oy = number("offset/x"), number("offset/y")
    colour_of = {}
    for node in root.findall("lens_type"):
        x, y = int(float(node.find("offset/x").text)), int(float(node.find("offset/y").text))
        colour_of[((-x) % 3 + y) % 3] = int(node.attrib["id"])
    left = Image.fromarray(srgb(picture)).resize((W * SCALE, H * SCALE), Image.NEAREST)
    draw = ImageDraw.Draw(left)
    c, s = math.cos(rotation), math.sin(rotation)
    centre = ((W - 1) / 2.0 + ox, (H - 1) / 2.0 - oy)  # (u, v): the offset's y is up
    radius = (diameter / 2 - border) * SCALE
    for alpha in range(-12, 13):
        for beta in range(-12, 13):
            row0, col0 = alpha * diameter * math.sqrt(3) / 2, (alpha / 2 + beta) * diameter
            u = centre[0] + s * row0 + c * col0
            v = centre[1] + c * row0 - s * col0
            if not (-diameter < u < W + diameter and -diameter < v < H + diameter):
                continue
            colour = COLOURS[colour_of[((-alpha) % 3 + beta) % 3]]
            x, y = (u + 0.5) * SCALE, (v + 0.5) * SCALE
            draw.ellipse([x - radius, y - radius, x + radius, y + radius], outline=colour, width=2)
            if alpha == 0 and beta == 0:
                draw.line([x - 6, y, x + 6, y], fill=(255, 255, 255), width=2)
                draw.line([x, y - 6, x, y + 6], fill=(255, 255, 255), width=2)
    seen = disparity[disparity > 0]
    low, high = (float(seen.min()), float(seen.max())) if seen.size else (0.0, 1.0)
    grey = np.where(disparity > 0, 40 + 215 * (disparity - low) / max(high - low, 1e-9), 0)
    right = Image.fromarray(np.clip(grey, 0, 255).astype(np.uint8)).resize(
        (W * SCALE, H * SCALE), Image.NEAREST).convert("RGB")
    figure = Image.new("RGB", (2 * W * SCALE + 20, H * SCALE), (255, 255, 255))
    figure.paste(left, (0, 0))
    figure.paste(right, (W * SCALE + 20, 0))
    figure.save(os.path.join(HERE, "raytrix_lattice.png"), optimize=True)


if __name__ == "__main__":
    main()
