# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-export --to raytrix and --to kiel (docs/export/raytrix.md): PlenopticToolbox 2.0's
RayCalibData XML beside the image, its disparity image, and its per-lens JSON of synthetic data.

Read back by readers written here from the format's documentation (the page's description of the
toolbox's reading: image centre ((W-1)/2, (H-1)/2), offset with y up, the lattice of horizontal
rows turned counter-clockwise on the screen by `rotation`, its lens types by their offsets'
colour ((-x mod 3) + y) mod 3), and checked against the render and the optics:
  - every lit lens of <stem>.microimages.csv has an XML lattice point within 0.01 px, one to one
    (a multi-focus array, turned 7 degrees and moved), and the diameter is p (D + d) / D / s;
  - each lens's XML type is our lens type (k_s - l) mod 3, and each type's depth range ends where
    libpleno's blur radius (p/2)(d/f + 1/v - 1) is one pixel, around the type's sharp f / (f - d);
  - the disparity of a fronto-parallel plane is diameter / v with v = (b - D) / d of its thin-lens
    image b (PFM within 1e-5 relative; the 16-bit PNG within one step of 1/v);
  - the per-lens JSON: every lit lens once, pixel_coord at its microimages.csv centre (also for an
    array with manufacturing errors, which the XML refuses by name), its colour image the picture
    sampled on the lens grid, its depth the plane's v times d;
  - refusals: a rectangular grid, a Keplerian camera for kiel, a render without a virtual depth
    map for kiel, manufacturing errors for raytrix.
"""
import json
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import plenoptic_testing as pt

W, H = 240, 180
F, N, D, D_MLA, PITCH, S = 49.885, 4.0, 56.86, 0.33713, 0.12744, 0.0055
FOCAL = (0.58267, 0.52402, 0.56057)
PLANE_MM = 370.0


def scene(array_extra="", grid="hexagonal", focal="focal_lengths <0.58267, 0.52402, 0.56057>", extra=""):
    return """#version 3.7;
global_settings { assumed_gamma 1.0 }
#declare Tex = texture { pigment { checker rgb 0.9 rgb 0.1 scale 0.0007 } finish { emission 1 diffuse 0 } }
camera {
  plenoptic
  location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length %g f_number %g distance %g }
  microlens_array { %s pitch %g %s distance %g %s }
  sensor { pixel_size %g }
  samples 4
  depth_map
  microimage_centres
  %s
}
plane { z, %g texture { Tex } }
""" % (F, N, D, grid, PITCH, focal, D_MLA, array_extra, S, extra, PLANE_MM / 1000.0)


def render(args, name, text):
    return pt.render(args.povray, os.path.join(args.work, name), name, text, W, H, extra=["+WT2"])


def export(args, image, fmt, out):
    return subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-export"), image, "--to", fmt, out, "-q"],
                          capture_output=True, text=True, timeout=300)


def read_csv_centres(path):
    """{(row-form k, l): (u, v)} of the lit lenses of <stem>.microimages.csv (docs/metadata.md)."""
    with open(path) as f:
        header = f.readline().strip().split(",")
        rows = [line.strip().split(",") for line in f if line.strip()]
    ik, il, iu, iv = (header.index(c) for c in ("k", "l", "u", "v"))
    return {(int(r[ik]), int(r[il])): (float(r[iu]), float(r[iv])) for r in rows if r[iu] and r[iv]}


def read_calib_xml(path):
    """The RayCalibData fields PlenopticToolbox 2.0 reads, as numbers."""
    root = ET.parse(path).getroot()
    assert root.tag == "RayCalibData", root.tag

    def pair(node, name, keys=("x", "y")):
        found = node.findall(name)
        assert len(found) == 1, "one <%s>, found %d" % (name, len(found))
        return tuple(float(found[0].find(k).text) for k in keys)

    cal = {"offset": pair(root, "offset"), "diameter": float(root.find("diameter").text),
           "rotation": float(root.find("rotation").text), "lens_border": float(root.find("lens_border").text),
           "lens_base_x": pair(root, "lens_base_x"), "lens_base_y": pair(root, "lens_base_y"),
           "sub_grid_base": pair(root, "sub_grid_base"), "types": []}
    i = 0
    while True:
        node = next((n for n in root.findall("lens_type") if n.attrib.get("id") == str(i)), None)
        if node is None:
            break
        cal["types"].append({"offset": pair(node, "offset"), "range": pair(node, "depth_range", ("min", "max"))})
        i += 1
    return cal


def toolbox_lattice(cal, width, height, reach=40):
    """{(alpha, beta): (u, v)}: the lens centres the toolbox's reading of the XML gives. Its bases
    (lens units, y up) are reflected into (row, col): (x, y) -> (-y, x); its axial bases are
    lbx = base_x and lby = base_x - base_y, scaled by the diameter; the grid is turned by R(rotation)
    acting on (row, col) and moved to the image centre plus the offset (row = -y, col = x)."""
    bx = np.array([-cal["lens_base_x"][1], cal["lens_base_x"][0]])
    by = np.array([-cal["lens_base_y"][1], cal["lens_base_y"][0]])
    lbx, lby = bx, bx - by
    c, s = math.cos(cal["rotation"]), math.sin(cal["rotation"])
    rot = np.array([[c, -s], [s, c]])
    centre = np.array([(height - 1) / 2.0, (width - 1) / 2.0]) + np.array([-cal["offset"][1], cal["offset"][0]])
    out = {}
    for alpha in range(-reach, reach + 1):
        for beta in range(-reach, reach + 1):
            row, col = centre + rot @ ((alpha * lby + beta * lbx) * cal["diameter"])
            out[(alpha, beta)] = (col, row)
    return out


def toolbox_types(cal):
    """{colour: XML type id}: a type's offset (x, y) has colour ((-x mod 3) + y) mod 3, as has each
    lens of axial (alpha, beta) with (x, y) = (alpha, beta)."""
    return {((-int(t["offset"][0])) % 3 + int(t["offset"][1])) % 3: i for i, t in enumerate(cal["types"])}


@pytest.fixture(scope="module")
def turned(args):
    """A multi-focus Galilean camera with its array turned 7 degrees and moved, and its exports."""
    image = render(args, "turned", scene("rotate <0, 0, 7> translate <0.013, -0.021, 0>"))
    out = {}
    for fmt in ("raytrix", "kiel"):
        folder = os.path.join(args.work, "turned_" + fmt)
        run = export(args, image, fmt, folder)
        assert run.returncode == 0, run.stderr
        out[fmt] = folder
    return image, out


def test_xml_places_every_microimage_centre(turned):
    image, out = turned
    stem = os.path.splitext(image)[0]
    cal = read_calib_xml(os.path.join(out["raytrix"], "turned.xml"))
    assert os.path.exists(os.path.join(out["raytrix"], "turned.png")), "the image beside the XML"
    expected_diameter = PITCH * (D + D_MLA) / D / S  # the lens centres projected from the main lens's centre
    assert abs(cal["diameter"] - expected_diameter) < 1e-9, (cal["diameter"], expected_diameter)
    assert abs(cal["rotation"] - math.radians(7)) < 1e-9, "the array's rotate <0, 0, 7>: %r rad" % cal["rotation"]
    centres = read_csv_centres(stem + ".microimages.csv")
    lattice = toolbox_lattice(cal, W, H)
    points = np.array(list(lattice.values()))
    keys = list(lattice.keys())
    matched = {}
    worst = 0.0
    for lens, (u, v) in centres.items():
        distance = np.hypot(points[:, 0] - u, points[:, 1] - v)
        j = int(np.argmin(distance))
        worst = max(worst, float(distance[j]))
        assert keys[j] not in matched, "two lenses on one XML lattice point"
        matched[keys[j]] = lens
    assert worst < 0.01, "an XML lattice point %.4g px from its microimages.csv centre" % worst
    inside = [k for k, (u, v) in lattice.items() if 0 <= u <= W - 1 and 0 <= v <= H - 1]
    assert set(inside) <= set(matched), "XML lattice points in the picture without a lens: %s" % (set(inside) - set(matched))
    assert len(centres) > 80, len(centres)
    # Lens types: the toolbox's colouring against ours, (k_s - l) mod 3 with k_s = k - floor(l / 2).
    colours = toolbox_types(cal)
    assert len(cal["types"]) == 3 and len(colours) == 3, cal["types"]
    for (alpha, beta), (k, l) in matched.items():
        ours = ((k - math.floor(l / 2)) - l) % 3
        assert colours[((-alpha) % 3 + beta) % 3] == ours, "lens (%d, %d): XML type %d, ours %d" % (
            k, l, colours[((-alpha) % 3 + beta) % 3], ours)
    # Depth ranges: the blur radius is one pixel at each end that is not clamped at v = 1.
    for t, entry in enumerate(cal["types"]):
        f = FOCAL[t]
        v_min, v_max = entry["range"]
        sharp = f / (f - D_MLA)
        assert v_min < sharp < v_max, (t, v_min, sharp, v_max)
        for v in (v_min, v_max):
            blur_px = abs(PITCH / 2.0 * (D_MLA / f + 1.0 / v - 1.0)) / S
            assert abs(blur_px - 1.0) < 1e-9, "type %d: blur %.6f px at v = %.6f" % (t, blur_px, v)
    # lens_border: the unlit rim around the f/4 microimage disc A d / D / s.
    disc = F / N * D_MLA / D / S
    assert abs(cal["lens_border"] - (cal["diameter"] - disc) / 2.0) < 1e-9


def test_disparity_of_a_plane(turned):
    image, out = turned
    b = F * PLANE_MM / (PLANE_MM - F)
    v = (b - D) / D_MLA  # positive: the plane's image lies behind the array
    diameter = PITCH * (D + D_MLA) / D / S
    from plenoptic_lf.images import read_image
    pfm = read_pfm(os.path.join(out["raytrix"], "turned_disp.pfm"))
    lit = np.isfinite(pfm)
    assert lit.mean() > 0.3, lit.mean()
    assert np.max(np.abs(pfm[lit] / (diameter / v) - 1)) < 1e-5, (np.nanmin(pfm), np.nanmax(pfm), diameter / v)
    png = read_image(os.path.join(out["raytrix"], "turned_disp.png"))
    assert png.shape == (H, W, 3) and np.array_equal(png[..., 0], png[..., 1]) and np.array_equal(png[..., 0], png[..., 2])
    assert np.max(np.abs(png[..., 0][lit] - 1.0 / v)) <= 0.5 / 65535 + 1e-7
    assert np.all(png[..., 0][~lit] == 0)


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"Pf"
        width, height = (int(x) for x in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4").reshape(height, width)
    return data[::-1]


def test_per_lens_json(turned, args):
    image, out = turned
    stem = os.path.splitext(image)[0]
    with open(os.path.join(out["kiel"], "turned.json")) as f:
        lenses = json.load(f)
    centres = read_csv_centres(stem + ".microimages.csv")
    assert len(lenses) == len(centres)
    seen = set()
    from plenoptic_lf.images import read_image
    picture = read_image(image)
    b = F * PLANE_MM / (PLANE_MM - F)
    v = (b - D) / D_MLA
    checked = 0
    for lens in lenses:
        k, l = lens["row_form_index"]
        u, vv = centres[(k, l)]
        assert abs(lens["pixel_coord"][1] - u) < 0.01 and abs(lens["pixel_coord"][0] - vv) < 0.01
        seen.add(tuple(lens["axial_coord"]))
        assert lens["focal_type"] == ((k - math.floor(l / 2)) - l) % 3
        f = FOCAL[lens["focal_type"]]
        assert abs(lens["focal_length"] - D_MLA) < 1e-12 and abs(lens["fstop"] - f / PITCH) < 1e-12
        assert abs(lens["focus_distance"] - f / (f - D_MLA) * D_MLA) < 1e-12
        n = int(math.ceil(lens["diameter"]))
        colour = read_image(os.path.join(out["kiel"], lens["relative_color_filename"]))
        depth = read_image(os.path.join(out["kiel"], lens["relative_depth_filename"]))[..., 0]
        assert colour.shape == (n, n, 3) and depth.shape == (n, n)
        # Sample (i, j) of the lens grid lies at offsets linspace(-r, r, n)[i, j] from the centre:
        # the picture there (bilinear), to 16 bits.
        offsets = np.linspace(-1, 1, n) * lens["diameter"] / 2
        for i, j in ((n // 2, n // 2), (n // 3, 2 * n // 3)):
            r, c = lens["pixel_coord"][0] + offsets[i], lens["pixel_coord"][1] + offsets[j]
            if not (0 <= r < H - 1 and 0 <= c < W - 1):
                continue
            r0, c0 = int(math.floor(r)), int(math.floor(c))
            fr, fc = r - r0, c - c0
            want = ((1 - fr) * (1 - fc) * picture[r0, c0] + (1 - fr) * fc * picture[r0, c0 + 1] +
                    fr * (1 - fc) * picture[r0 + 1, c0] + fr * fc * picture[r0 + 1, c0 + 1])
            assert np.max(np.abs(colour[i, j] - want)) < 2e-5, (lens["axial_coord"], i, j, colour[i, j], want)
            checked += 1
        z = depth * (lens["clip_end"] - lens["clip_start"]) + lens["clip_start"]
        hit = z > 0
        assert hit.any()
        assert np.max(np.abs(z[hit] / lens["focal_length"] - v)) < v * 2e-4, "the plane's virtual depth"
    assert len(seen) == len(lenses), "axial coordinates unique"
    assert checked > len(lenses), checked


def test_manufacturing_errors_refused_by_raytrix_written_by_kiel(args):
    image = render(args, "errors", scene("errors { position 0.002 focal_length 0.005 seed 5 }"))
    run = export(args, image, "raytrix", os.path.join(args.work, "errors_raytrix"))
    assert run.returncode == 2 and "lies" in run.stderr and "px from the lattice" in run.stderr, run.stderr
    assert not os.path.exists(os.path.join(args.work, "errors_raytrix"))
    folder = os.path.join(args.work, "errors_kiel")
    run = export(args, image, "kiel", folder)
    assert run.returncode == 0, run.stderr
    with open(os.path.join(folder, "errors.json")) as f:
        lenses = json.load(f)
    centres = read_csv_centres(os.path.splitext(image)[0] + ".microimages.csv")
    off = 0.0
    for lens in lenses:
        u, v = centres[tuple(lens["row_form_index"])]
        assert abs(lens["pixel_coord"][1] - u) < 1e-9 and abs(lens["pixel_coord"][0] - v) < 1e-9
        off = max(off, abs(lens["pixel_coord"][1] - u))
    assert len(lenses) == len(centres)


@pytest.mark.parametrize("name, text, fmt, words", [
    ("rect", scene(grid="rectangular", focal="focal_length 0.58267"), "raytrix", "hexagonal"),
    ("keplerian", scene(focal="focal_length 0.3"), "kiel", "Galilean"),
    ("no_depth", scene().replace("  depth_map\n", ""), "kiel", "depth_map"),
])
def test_refusals(args, name, text, fmt, words):
    image = render(args, name, text)
    run = export(args, image, fmt, os.path.join(args.work, name + "_out"))
    assert run.returncode == 2 and words in run.stderr, run.stderr
    assert len(run.stderr.strip().splitlines()) == 1, run.stderr
