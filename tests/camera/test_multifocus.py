# SPDX-License-Identifier: AGPL-3.0-or-later
"""Multi-focus arrays (focal_lengths <f0, f1, f2>): every lens type has its own blur.

A focused (2.0, Keplerian) camera looks at a fine checkerboard at z = 300 mm. The main
lens (F = 25 mm) images it to b = F z / (z - F) behind itself; the array sits a = 2 mm
behind that image (D = b + a), the sensor d = 0.5 mm behind the array. A microlens of
focal length f images the intermediate image sharply on the sensor when
1/f = 1/a + 1/d, i.e. f = 0.4 mm; with the cone from the main aperture wider than a
lens cell at the array, each lens uses its whole cell (width ~ pitch p), and the blur
on the sensor is p |1 - d (1/f - 1/a)|: 0 px for f = 0.40, about 3.5 px for 0.45 and
8.5 px for 0.55 (4 um pixels, p = 0.15 mm).

The specification (docs/specification.md, section 2) asks that no two neighbouring lenses
share a type and that the metadata state the rule; docs/metadata.md gives it: with skew
index k_s = k - floor(l/2), type(k, l) = (k_s - l) mod 3, and lens (k, l) has
focal_lengths[type]. The test measures the sharpness (gradient energy at the middle of each
microimage) and checks that
1. the median sharpness of the three types is ordered as the predicted blurs;
2. classifying each microimage by its sharpness alone gives the rule's type;
3. the measured classes never repeat between neighbours (the neighbour rule, from the
   image alone);
4. permuting focal_lengths moves the sharp microimages to the lenses the rule says.
"""
import math
import os

import numpy as np

import plenoptic_testing as pt

W, H = 256, 192
SX = 0.004
F_MAIN, F_NUMBER = 25.0, 5.0
Z_TARGET = 300.0      # mm
A_GAP = 2.0           # intermediate image -> array, mm
D_ARRAY = 0.5         # array -> sensor, mm
PITCH = 0.15
SAMPLES = 32


def lens_type(k, l):
    ks = k - (l // 2)          # Python's // is floor division
    return (ks - l) % 3


def predicted_blur_px(f):
    return PITCH * abs(1 - D_ARRAY * (1 / f - 1 / A_GAP)) / SX


def render(args, name, focal_lengths):
    b = F_MAIN * Z_TARGET / (Z_TARGET - F_MAIN)
    D = b + A_GAP
    # Checker squares of 0.7 mm: about 4 px in a sharp microimage (magnification
    # (b / z) (d / a) = 0.0227).
    scene = ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 0 }\n"
             "plane { z, %r pigment { checker rgb 1 rgb 0.05 scale 0.0007 translate <0.00013, 0.00029, 0> }"
             " finish { ambient 1 diffuse 0 } }\n"
             "camera { plenoptic location <0, 0, 0>\n"
             "  main_lens { thin_lens focal_length %r f_number %r distance %.17g }\n"
             "  microlens_array { hexagonal pitch %r focal_lengths <%r, %r, %r> distance %r }\n"
             "  sensor { pixel_size %r } samples %d }\n"
             % ((Z_TARGET / 1000.0, F_MAIN, F_NUMBER, D, PITCH) + tuple(focal_lengths)
                + (D_ARRAY, SX, SAMPLES)))
    path = pt.render(args.povray, args.work, name, scene, W, H)
    img = pt.load(path)[:, :, 0]
    return img, pt.metadata_of(path), D


def sharpness(img, D):
    """(k, l) -> gradient energy inside a radius of 0.55 x the microimage disc radius."""
    sensor_z = -(D + D_ARRAY)
    disc_px = (F_MAIN / F_NUMBER) * D_ARRAY / D / 2 / SX
    r = 0.55 * disc_px
    gx = np.zeros_like(img)
    gy = np.zeros_like(img)
    gx[:, :-1] = np.diff(img, axis=1)
    gy[:-1, :] = np.diff(img, axis=0)
    energy = gx ** 2 + gy ** 2
    vv, uu = np.mgrid[0:H, 0:W]
    out = {}
    for l in range(-12, 13):
        for k in range(-12, 13):
            c = pt.posed_lens_centre("hexagonal", PITCH, k, l, (0, 0, 0), (0, 0, 0), D)
            s = sensor_z / c[2]
            u, v = pt.sensor_to_pixel(c[0] * s, c[1] * s, W, H, SX, SX)
            if not (disc_px + 1 < u < W - 2 - disc_px and disc_px + 1 < v < H - 2 - disc_px):
                continue
            sel = (uu - u) ** 2 + (vv - v) ** 2 <= r * r
            out[(k, l)] = float(energy[sel].mean())
    return out


def neighbours(k, l):
    """Row-form neighbours of a hexagonal lens (odd rows shifted +x by half a pitch)."""
    if l % 2 == 0:
        return [(k - 1, l), (k + 1, l), (k - 1, l - 1), (k, l - 1), (k - 1, l + 1), (k, l + 1)]
    return [(k - 1, l), (k + 1, l), (k, l - 1), (k + 1, l - 1), (k, l + 1), (k + 1, l + 1)]


def analyse(name, sharp, focal_lengths):
    blur = [predicted_blur_px(f) for f in focal_lengths]
    med = [float(np.median([s for (k, l), s in sharp.items() if lens_type(k, l) == t])) for t in range(3)]
    by_blur = sorted(range(3), key=lambda t: blur[t])
    by_sharp = sorted(range(3), key=lambda t: -med[t])
    assert (by_blur == by_sharp and med[by_sharp[0]] > 1.5 * med[by_sharp[1]] and
                 med[by_sharp[1]] > 1.5 * med[by_sharp[2]]), (name + ": sharpness per type follows the predicted blur" + ": " + ("focal lengths %s mm -> predicted blur %s px; median gradient energy per type %s "
                 "(ordered as the blurs, each at least 1.5 times the next)"
                 % (list(focal_lengths), [round(b, 2) for b in blur], [round(m, 5) for m in med])))
    # Classify each microimage by its sharpness alone (nearest type median, in log scale).
    logm = np.log(med)
    cls = {key: int(np.argmin(np.abs(logm - math.log(max(s, 1e-12))))) for key, s in sharp.items()}
    wrong = [(key, lens_type(*key), cls[key]) for key in sharp if cls[key] != lens_type(*key)]
    assert (not wrong and len(sharp) >= 30), (name + ": each microimage's blur is its type's" + ": " + ("%d microimages measured, %d classified as another type %s"
                 % (len(sharp), len(wrong), wrong[:5])))
    pairs = same = 0
    for key in sharp:
        for nb in neighbours(*key):
            if nb in sharp:
                pairs += 1
                same += cls[key] == cls[nb]
    assert (pairs > 50 and same == 0), name + ": no two neighbours look alike" + ": " + ("%d neighbouring pairs measured, %d share a sharpness class (expected 0)" % (pairs // 2, same // 2))


def test_multifocus(args):
    focal = (0.40, 0.42, 0.55)
    img, meta, D = render(args, "multifocus", focal)
    lattice = meta.get("microimage_lattice") or {}
    assert (lattice.get("lens_types") == 3 and
                 lattice.get("lens_type_rule", "").startswith("type(k, l) = (k - l) mod 3")), ("metadata states the rule" + ": " + ("lens_types %r, lens_type_rule %r (expected 3 and the skew-index rule of docs/metadata.md)"
                 % (lattice.get("lens_types"), lattice.get("lens_type_rule"))))
    analyse("focal_lengths <0.40, 0.42, 0.55>", sharpness(img, D), focal)
    permuted = (0.55, 0.40, 0.42)
    img2, _, _ = render(args, "multifocus_permuted", permuted)
    analyse("focal_lengths <0.55, 0.40, 0.42>", sharpness(img2, D), permuted)
    pt.save_png(os.path.join(args.work, "multifocus_view.png"), np.concatenate([img, img2], axis=1))

