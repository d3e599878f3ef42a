# SPDX-License-Identifier: AGPL-3.0-or-later
"""Blocked light is black and opaque; the degenerate pinhole/pinhole pair is refused.

docs/specification.md, section 3: a ray that misses the main-lens aperture carries no light; a
pixel's value is the mean over its samples with blocked samples black; a pixel no ray
reaches is black and opaque, never background. Section 4 / the table: a pinhole main
lens with a pinhole array is refused at parse time with a clear message.

1. Plenoptic cameras with gaps between their microimages (main lens stopped down to
   f/8, well beyond f-number matching) look at an empty scene whose background is
   green, rendered with +UA (alpha). Stock POV-Ray gives background pixels alpha 0.
   The test predicts from docs/specification.md which pixels lie wholly outside every
   microimage (further from the projection of their lens centre than the aperture's
   image plus the spread of a lens cell plus half a pixel diagonal) and which lie
   wholly inside, and requires: outside = RGB 0 and alpha 1 exactly; inside = alpha 0
   (background). With an opaque green background and no +UA, the outside pixels must
   still be black, never green, and the inside ones green.
2. `main_lens { pinhole ... }` with `microlens_array { ... pinhole ... }` must fail at
   parse time: non-zero exit, a message that names the problem, and POV-Ray's usual
   File/Line pointing into the camera block.
"""
import math
import re

import numpy as np
import pytest

import plenoptic_testing as pt

W, H = 160, 120
SX = 0.006
F_MAIN, F_NUMBER, FOCUS = 25.0, 8.0, 1.0
BACKGROUND = (0.2, 0.9, 0.3)


def camera(grid, lens, d, pitch):
    lens_kw = "pinhole" if lens == "pinhole" else "focal_length %r" % lens
    return ("camera { plenoptic location <0, 0, 0>\n"
            "  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }\n"
            "  microlens_array { %s pitch %r %s distance %r }\n"
            "  sensor { pixel_size %r } samples 16 }\n" % (F_MAIN, F_NUMBER, FOCUS, grid, pitch, lens_kw, d, SX))


def classify(grid, lens, d, pitch):
    """Boolean masks (wholly dark, wholly lit) of the pixels, from docs/specification.md."""
    D = pt.thin_lens_D(F_MAIN, FOCUS * 1000.0)
    k = D / d
    g = 1 + k if lens == "pinhole" else 1 + k - D / lens
    circ = pitch / math.sqrt(3) if grid == "hexagonal" else pitch / math.sqrt(2)
    disc = (F_MAIN / F_NUMBER) / 2 / k / SX
    spread = 0 if lens == "pinhole" else circ * abs(g) / k / SX
    half_diag = math.sqrt(0.5)
    centres = []
    for l in range(-20, 21):
        for kk in range(-20, 21):
            c = pt.posed_lens_centre(grid, pitch, kk, l, (0, 0, 0), (0, 0, 0), D)
            s = -(D + d) / c[2]
            centres.append(pt.sensor_to_pixel(c[0] * s, c[1] * s, W, H, SX, SX))
    centres = np.array(centres)
    vv, uu = np.mgrid[0:H, 0:W]
    nearest = np.full((H, W), np.inf)
    for u, v in centres:
        nearest = np.minimum(nearest, np.hypot(uu - u, vv - v))
    dark = nearest > disc + spread + half_diag + 0.5
    lit = nearest < disc - spread - half_diag - 0.5
    return dark, lit, disc, spread


@pytest.mark.parametrize("name, grid, lens, d, pitch", [
    ("plenoptic1_hex", "hexagonal", 0.5, 0.5, 0.12),
    ("chief_ray_rect", "rectangular", "pinhole", 0.5, 0.12),
    ("focused2_hex", "hexagonal", 0.42, 0.5, 0.12),
])
def test_blocked_pixels(args, name, grid, lens, d, pitch):
    head = "#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n"
    transparent = head + "background { rgbt <%r, %r, %r, 1> }\n" % BACKGROUND + camera(grid, lens, d, pitch)
    opaque = head + "background { rgb <%r, %r, %r> }\n" % BACKGROUND + camera(grid, lens, d, pitch)
    rgba = pt.load(pt.render(args.povray, args.work, name + "_alpha", transparent, W, H, extra=["+UA"]))
    rgb = pt.load(pt.render(args.povray, args.work, name + "_opaque", opaque, W, H))
    dark, lit, disc, spread = classify(grid, lens, d, pitch)
    assert rgba.shape[2] == 4, name + ": +UA output has alpha" + ": " + ("channels: %d" % rgba.shape[2])
    if rgba.shape[2] != 4:
        return
    a = rgba[:, :, 3]
    dark_rgb = float(np.abs(rgba[dark][:, :3]).max())
    dark_alpha = float(a[dark].min())
    assert (dark.sum() > 1000 and dark_rgb == 0 and dark_alpha == 1), (name + ": blocked pixels are black, opaque" + ": " + ("%d pixels wholly outside every microimage (disc %.1f px + spread %.1f px): max RGB %.3g "
                 "(expected 0), min alpha %.4f (expected 1)" % (dark.sum(), disc, spread, dark_rgb, dark_alpha)))
    lit_alpha = float(a[lit].max())
    assert (lit.sum() > 500 and lit_alpha == 0), name + ": lit pixels show the background (alpha 0)" + ": " + ("%d pixels wholly inside a microimage: max alpha %.4f (expected 0)" % (lit.sum(), lit_alpha))
    opaque_dark = float(np.abs(rgb[dark][:, :3]).max())
    lit_err = float(np.abs(rgb[lit][:, :3] - np.array(BACKGROUND)).max())
    assert (opaque_dark == 0 and lit_err < 1e-3), (name + ": without alpha: black where blocked, background where lit" + ": " + ("max RGB of blocked pixels %.3g (expected 0); max |lit - background| %.2g (expected 0 up "
                 "to 16-bit rounding)" % (opaque_dark, lit_err)))


def test_pinhole_pinhole_refused(args):
    scene = ("#version 3.7;\n"            # line 1
             "global_settings { assumed_gamma 1.0 }\n"
             "camera {\n"                 # line 3
             "  plenoptic\n"
             "  main_lens { pinhole distance 30 }\n"
             "  microlens_array { hexagonal pitch 0.1 pinhole distance 0.4 }\n"
             "}\n"                        # line 7
             "sphere { <0, 0, 5>, 1 pigment { rgb 1 } }\n")
    rc, text = pt.render(args.povray, args.work, "pinhole_pinhole", scene, 32, 24, expect_failure=True)
    m = re.search(r"line:?\s*(\d+)", text, re.IGNORECASE)
    line = int(m.group(1)) if m else None
    named = "degenerate" in text and "pinhole" in text
    assert (rc != 0 and named and line is not None and 3 <= line <= 7), ("pinhole main lens + pinhole array is refused" + ": " + ("exit code %d (expected non-zero), message names the problem: %s, reported line %s "
                 "(expected within the camera block, lines 3-7); console: %s"
                 % (rc, named, line, " | ".join(l for l in text.splitlines() if "rror" in l or "degenerate" in l)[:400])))

