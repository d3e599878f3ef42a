#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""The figure of docs/export/eslf.md: a crop of a raw plenoptic 1.0 render (hexagonal array) looking at a checkerboard behind the plane in focus
beside the same lenslets in the ESLF that `plenoptic-export --to eslf` writes (one tile of
angular samples per lenslet, hexagonal rows resampled), and the centre view (one sample of every
tile).

    /usr/bin/python3 docs/export/make_figure.py build/povray

renders the scene (a few seconds), exports it with tools/plenoptic-export and writes
docs/export/eslf_tiles.png."""
import os
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image, ImageDraw

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
W, H = 320, 240
SCENE = """#version 3.7;
global_settings { assumed_gamma 1 }
#declare Tex = texture {
  pigment { checker rgb <0.9, 0.85, 0.5> rgb <0.1, 0.2, 0.5> scale 0.004 rotate z*20 }
  finish { emission 1 diffuse 0 ambient 0 } }
camera { plenoptic location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length 50 f_number 2 focus_distance 1 }
  microlens_array { hexagonal pitch 0.1 focal_length 0.2 distance 0.2 }
  sensor { pixel_size 0.01 }
  samples 16 }
plane { z, 1.15 texture { Tex } }
"""


def srgb(x):
    x = np.clip(x, 0, 1)
    return (np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055) * 255 + 0.5).astype(np.uint8)


def main():
    povray = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "povray")
    sys.path.insert(0, os.path.join(ROOT, "python"))
    import json
    import OpenImageIO as oiio
    import plenoptic_lf as plf
    with tempfile.TemporaryDirectory() as work:
        pov = os.path.join(work, "scene.pov")
        with open(pov, "w") as f:
            f.write(SCENE)
        png = os.path.join(work, "scene.png")
        subprocess.run([povray, "+I" + pov, "+O" + png, "+W%d" % W, "+H%d" % H, "-D", "-P", "-GA", "+FN16",
                        "File_Gamma=1.0"], check=True, cwd=work, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        out = os.path.join(work, "out")
        subprocess.run([sys.executable, os.path.join(ROOT, "tools", "plenoptic-export"), png, "--to", "eslf", out,
                        "-q"], check=True, stdout=subprocess.DEVNULL)
        raw = plf.read_raw(png)
        config = oiio.ImageSpec()
        config.attribute("oiio:UnassociatedAlpha", 1)
        image = oiio.ImageInput.open(os.path.join(out, "scene.eslf.png"), config)
        eslf = image.read_image(oiio.UINT16).astype(np.float64) / 65535.0
        image.close()
        with open(os.path.join(out, "scene.eslf.png.json")) as f:
            doc = json.load(f)
    n_v, n_u, T, S = doc["DecodeOptions"]["LFSize"][:4]
    grid = doc["plenoptic"]["resampled_grid"]
    lattice = doc["plenoptic"]["microimage_lattice"]
    A, R = np.array(grid["A_px"]), np.array(grid["R_px"])
    s0, t0 = grid["s0_t0"]
    # The crop: lenslets t 6..11, s 8..15 of the ESLF, and the raw region under them.
    ts, ss = slice(6, 12), slice(8, 16)
    tiles = eslf[ts.start * n_v:ts.stop * n_v, ss.start * n_u:ss.stop * n_u]
    rgb = tiles[..., :3] * (tiles[..., 3:] > 0.5) + 0.25 * (tiles[..., 3:] <= 0.5)
    corner = np.array(lattice["origin_px"]) + (s0 + ss.start - 0.5) * A + (t0 + ts.start - 0.5) * R
    x0, y0 = int(np.floor(corner[0])), int(np.floor(corner[1]))
    width = int(np.ceil((ss.stop - ss.start) * np.hypot(*A)))
    height = int(np.ceil((ts.stop - ts.start) * np.hypot(*R)))
    crop = raw[y0:y0 + height, x0:x0 + width]
    centre = eslf[n_v // 2::n_v, n_u // 2::n_u, :3]
    zoom = 4
    panels = [("raw (hexagonal lenslets)", srgb(crop), zoom),
              ("ESLF: %d x %d tiles, grey = weight 0" % (n_u, n_v), srgb(rgb), zoom),
              ("centre view", srgb(centre), zoom)]
    pictures = [Image.fromarray(p).resize((p.shape[1] * z, p.shape[0] * z), Image.NEAREST) for _, p, z in panels]
    gap, label = 12, 18
    figure = Image.new("RGB", (sum(p.width for p in pictures) + gap * (len(pictures) + 1),
                               max(p.height for p in pictures) + label + gap * 2), "white")
    draw = ImageDraw.Draw(figure)
    x = gap
    for (title, _, _), picture in zip(panels, pictures):
        draw.text((x, gap // 2), title, fill="black")
        figure.paste(picture, (x, gap + label))
        x += picture.width + gap
    path = os.path.join(HERE, "eslf_tiles.png")
    figure.save(path, optimize=True)
    print("wrote %s (%d x %d)" % (path, figure.width, figure.height))


if __name__ == "__main__":
    main()
