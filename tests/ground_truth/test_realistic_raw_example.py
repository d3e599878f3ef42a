# SPDX-License-Identifier: AGPL-3.0-or-later
"""The worked example of a realistic raw (scenes/realistic_raw.pov; docs/worked-examples.md,
section 3) renders and decodes end to end, and its numbers are the optics'.

Checked against answers that are not the camera's or the decoder's:
  - the lens's paraxial data at f/4 focused at 2 m, the working f-number, the microimage
    diameter and spacing the page prints, from the tests' own reference tracer
    (plenoptic_testing.lens_tracer) and the projection of the lens centres from the exit pupil;
  - the lit discs of the white image (a 10-bit Bayer raw with noise, diffraction, cos^4 and an
    angular response): their mean area gives the diameter the optics predict;
  - the raw, decoded and devignetted by the white image as the page does it, carries the same
    light field as the noise-free picture decoded the same way: no bias beyond 1 %, and a spread
    within what the shot noise of 3000 electrons a unit allows.
"""
import json
import math
import os
import subprocess
import sys

import numpy as np

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt

SCENES = os.path.join(pt.SOURCE_DIR, "scenes")
LENS_FILE = os.path.join(pt.SOURCE_DIR, "lenses", "wide_angle_22mm_laikin_f3.5.dat")
W, H = 320, 224            # a crop around the sensor's centre (the page renders 1544 x 1072)
F_NUMBER, FOCUS_MM = 4.0, 2000.0
PITCH, D_ARRAY, PIXEL = 0.100, 0.400, 0.007
EXPOSURE_E = 3000.0


def render(args):
    out = os.path.join(args.work, "realistic_raw.png")
    for suffix in (".png", ".raw.png", ".white.png", ".plenoptic.json", ".microimages.csv"):
        path = out[:-4] + suffix
        if os.path.exists(path):
            os.remove(path)
    run = pt.run_povray(args.povray, os.path.join(SCENES, "realistic_raw.pov"), out, W, H,
                        extra=("+L" + SCENES, "+WT2"), timeout=400)
    assert run.returncode == 0 and not run.timed_out, pt.tail(run.output, 30)
    return out[:-4]


def reference_optics():
    """The camera's first-order numbers from the reference tracer: the stop sized for f/4, the
    array at the paraxial image of the plane 2 m in front of the front vertex."""
    rows = lt.parse_lens_file(open(LENS_FILE).read())
    wide_open = lt.Lens(rows)
    p0 = lt.paraxial_data(wide_open)
    stop = wide_open.stop_diameter * (p0.efl / F_NUMBER) / p0.entrance_pupil_diameter
    lens = lt.Lens(rows, stop_diameter=stop)
    p = lt.paraxial_data(lens)
    D = lt.paraxial_image_distance(lens, FOCUS_MM)           # rear vertex -> array
    exit_to_array = D + lens.length - p.exit_pupil_z          # exit pupil -> array
    return {
        "efl": p.efl, "f_number": p.f_number, "D": D,
        "working_f_number": (exit_to_array + 0.0) / p.exit_pupil_diameter,
        "diameter_px": p.exit_pupil_diameter * D_ARRAY / exit_to_array / PIXEL,
        "spacing_px": PITCH * (exit_to_array + D_ARRAY) / exit_to_array / PIXEL,
    }


def test_realistic_raw_renders_decodes_and_matches_the_optics(args):
    stem = render(args)
    meta = pt.load_metadata(stem + ".plenoptic.json")
    ref = reference_optics()

    # The numbers of the page, from the reference tracer.
    paraxial = meta["main_lens"]["paraxial"]
    assert abs(paraxial["effective_focal_length_mm"] - ref["efl"]) < 1e-9 * ref["efl"]
    assert abs(meta["main_lens"]["f_number"] - F_NUMBER) < 1e-9
    assert abs(meta["main_lens"]["distance_mm"] - ref["D"]) < 1e-9 * ref["D"]
    assert abs(paraxial["working_f_number"] - ref["working_f_number"]) < 1e-9 * ref["working_f_number"]
    # The microlenses are matched: f / p = 4 against the lens's working f-number (4.02).
    assert abs(ref["working_f_number"] / (D_ARRAY / PITCH) - 1) < 0.01, ref
    lattice = meta["microimage_lattice"]
    assert abs(lattice["microimage_diameter_px"] - ref["diameter_px"]) < 1e-6, (lattice, ref)
    spacing = math.hypot(*lattice["basis_px"][0])
    assert abs(spacing - ref["spacing_px"]) < 1e-6, (spacing, ref)

    # The white image's lit discs: 10-bit DN with black level 64, a GRBG mosaic and noise. A
    # pixel is lit above half the microimages' typical peak; the mean lit area per microimage
    # over the inner part of the crop is that of a disc of the predicted diameter (the rim is
    # soft by diffraction, 0.4 px, and the pixel: 3 % of the diameter).
    read_out = meta["sensor"]["read_out"]
    white = np.rint(pt.read_pixels(stem + ".white.png")[..., 0] * 65535.0) - read_out["black_level_dn"]
    margin = 2 * int(spacing)
    inner = white[margin:H - margin, margin:W - margin]
    peak = np.percentile(inner, 95)
    lit_pixels = float((inner > 0.5 * peak).sum())
    hexagon_area = spacing ** 2 * math.sqrt(3) / 2          # one microimage cell, px^2
    lenses = inner.size / hexagon_area
    diameter = 2 * math.sqrt(lit_pixels / lenses / math.pi)
    assert abs(diameter / ref["diameter_px"] - 1) < 0.03, (diameter, ref["diameter_px"])

    # Decode as the page does: the raw, devignetted by the white image; and the noise-free
    # picture the same way. The raw's light field is the picture's within the shot noise.
    fields = {}
    for name, source in (("raw", stem + ".raw.png"), ("picture", stem + ".png")):
        out = os.path.join(args.work, "decoded_" + name)
        cmd = [sys.executable, os.path.join(args.tools, "plenoptic-decode"), source, "--white", stem + ".white.png",
               "-o", out, "--no-gif"]
        if name == "raw":
            cmd += ["--contact-sheet", os.path.join(args.work, "contact-sheet.png")]
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr[-3000:]
        fields[name] = np.load(os.path.join(out, "lightfield.npy"))
    assert os.path.getsize(os.path.join(args.work, "contact-sheet.png")) > 10000
    raw, picture = fields["raw"], fields["picture"]
    assert raw.shape == picture.shape and raw.shape[0] >= 8 and raw.shape[1] >= 12, raw.shape
    # Samples the picture sees well lit (the devignetted picture is about the scene's radiance),
    # at angular offsets at least 2 px inside the microimage's rim: the bilinear demosaic blends
    # each pixel with its neighbours 1 px away, and across the rim's steep fall-off that blend
    # differs from the picture's by design (the white image's own demosaic does not undo it).
    n = raw.shape[2]
    offsets = np.arange(n) - n // 2
    dv, du = np.meshgrid(offsets, offsets, indexing="ij")
    inside = np.hypot(du, dv) <= ref["diameter_px"] / 2 - 2
    assert inside.sum() >= 49, inside.sum()
    raw, picture = raw[:, :, inside], picture[:, :, inside]
    lit = (picture > 0.15) & (picture < 2.0)
    assert lit.mean() > 0.3, lit.mean()
    ratio = raw[lit] / picture[lit]
    # No bias: DN back to light, demosaicing and devignetting agree with the picture (the raw's
    # expectation is the picture; the 8-bit picture file rounds by at most 0.2 %).
    assert abs(np.median(ratio) - 1) < 0.01, np.median(ratio)
    assert abs(raw[lit].sum() / picture[lit].sum() - 1) < 0.01, raw[lit].sum() / picture[lit].sum()
    # The spread: the shot noise of a sample of value v has a relative rms of 1 / sqrt(3000 v)
    # (read noise, dark signal and the 1 % gain pattern add less than a fifth of that at
    # v > 0.15); the decoder's interpolations only average it down. The median absolute
    # deviation of a normal variable is 0.674 sigma; demosaicing of texture adds a little:
    # allow 1.2 times that.
    sigma = 1.0 / np.sqrt(EXPOSURE_E * picture[lit])
    mad = np.median(np.abs(ratio - 1) / sigma)
    assert mad < 1.2 * 0.674, mad
