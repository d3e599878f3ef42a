# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-export --to compote (docs/export/compote.md): COMPOTE / libpleno's configuration files
and observation CSVs for a plenoptic-targets checkerboard set.

A reader written here from the format's documentation (COMPOTE's configuration files as JSON;
libpleno's hexagonal rows-aligned grid, node (k, l) = R (p (k + 1/2 [l even]), p sin60 l) + t; its
lens type ((l mod 2) + k) mod 3; image UV = (W-1-x, H-1-y) of the sensor's metric x, y over its
scale; micro-lens indices the micro-image ones reversed) parses every file, and the numbers are
checked against the render and the optics:
  - camera and intrinsics: sensor scale and size, main lens f and f-number, D, d, the array's
    pitch (mm) and the micro-image pitch p (D + d) / D / s;
  - every centre of obs/center.csv is its mesh node and a lit lens's microimages.csv centre
    within 0.01 px; every micro-lens node, projected from the main lens's centre onto the sensor
    of the intrinsics, lands on its micro-image node; its focal length (mla.focal_lengths by
    libpleno's type) is our lens's, (k_s - l) mod 3 of a multi-focus array;
  - params: dc = micro-image pitch x scale, dC the pitch, lambda = D / (D + d), q' = q + dc/2, and
    the micro-image radius m / N + q_i equals the thin-lens one, F d / (2 D N) + (p/2)|1 - d/f_i + d/D|,
    with libpleno's sign (negative for a Galilean camera);
  - obs/bap.csv: every image of every corner, rho = plenoptic-project --blur (the render's truth)
    and = libpleno's (p/2)(d/f + 1/v - 1) / s from the corner's thin-lens image (1e-4 px); each
    cluster is the corner's index in the scene's checkerboard (x_grid, y_grid, lph = the square);
  - refusals: a render that is not a target view, a circle grid.
"""
import csv
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import plenoptic_testing as pt

W, H = 240, 180
F, N, D, D_MLA, PITCH, S = 49.885, 4.0, 56.86, 0.33713, 0.12744, 0.0055
FOCAL = (0.58267, 0.52402, 0.56057)
SIN60 = math.sqrt(3.0) / 2.0
CAMERA = ("camera { plenoptic\n"
          "  main_lens { thin_lens focal_length %g f_number %g distance %g }\n"
          "  microlens_array { hexagonal pitch %g focal_lengths <%g, %g, %g> distance %g rotate <0, 0, 3> translate <0.011, 0.007, 0> }\n"
          "  sensor { pixel_size %g } samples 4 microimage_centres }\n" % (F, N, D, PITCH, *FOCAL, D_MLA, S))


def targets(args, name, target):
    work = os.path.join(args.work, name)
    os.makedirs(work, exist_ok=True)
    cam = pt.write_text(os.path.join(work, "camera.inc"), CAMERA)
    out = os.path.join(work, "set")
    run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-targets"), cam, "--out", out,
                          "--count", "2", "--seed", "4", "--distance", "0.36", "0.38", "--tilt", "10",
                          "--target", target, "--width", str(W), "--height", str(H), "--povray", args.povray,
                          "--project", args.project], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return out


def export(args, image, out):
    return subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-export"), image, "--to", "compote",
                           out, "-q", "-O", "project=" + args.project], capture_output=True, text=True, timeout=300)


def read_js(path):
    with open(path) as f:
        return json.load(f)


def read_rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def lens_type(k, l):
    return ((l % 2) + k) % 3


def mesh_node(mesh, k, l):
    """libpleno's node of a hexagonal rows-aligned mesh, in its world (2-D or 3-D)."""
    px, py = mesh["pitch"][0]
    local = np.array([px * (k + (0.5 if l % 2 == 0 else 0.0)), py * l * SIN60])
    rot = np.array(mesh["pose"]["rotation"], dtype=float)
    t = np.array(mesh["pose"]["translation"][0], dtype=float)
    if rot.shape == (3, 3):
        local = np.append(local, 0.0)
    return rot @ local + t


@pytest.fixture(scope="module")
def exported(args):
    folder = targets(args, "checkerboard", "checkerboard:6x8:0.001")
    out = os.path.join(args.work, "compote")
    run = export(args, os.path.join(folder, "target_000.png"), out)
    assert run.returncode == 0, run.stderr
    return folder, out


def test_configuration_and_centres(exported):
    folder, out = exported
    camera = read_js(os.path.join(out, "config", "camera.js"))
    intr = read_js(os.path.join(out, "config", "intrinsics.js"))
    params = read_js(os.path.join(out, "config", "params.js"))
    scene = read_js(os.path.join(out, "config", "scene.js"))
    assert camera["sensor"] == {"scale": S, "width": W, "height": H}
    assert camera["main_lens"] == {"aperture": N, "f": F} and camera["I"] == 3 and camera["mode"] == 2
    assert intr["D"] == D and intr["d"] == D_MLA and intr["main_lens"]["diameter"] == F / N
    mla, mia = intr["mla"]["mesh"], intr["mia"]["mesh"]
    assert mla["pitch"] == [[PITCH, PITCH]] and mla["geometry"] == 1 and mia["geometry"] == 1
    spacing = PITCH * (D + D_MLA) / D / S
    assert abs(mia["pitch"][0][0] - spacing) < 1e-9 and abs(mia["pitch"][0][1] - spacing) < 1e-9
    assert camera["mia"] == intr["mia"]
    assert scene["checkerboards"][0]["lph"] == 1.0 and scene["checkerboards"][0]["x_grid"] == 7 \
        and scene["checkerboards"][0]["y_grid"] == 5
    # Centres: on their nodes, and on the render's measured centres.
    measured = {}
    for row in read_rows(os.path.join(folder, "target_000.microimages.csv")):
        if row["u"]:
            measured[(int(row["k"]), int(row["l"]))] = (float(row["u"]), float(row["v"]))
    keys, points = list(measured), np.array(list(measured.values()))
    rows = read_rows(os.path.join(out, "obs", "center.csv"))
    assert len(rows) == len(measured)
    width, height = mia["width"], mia["height"]
    sensor_t = np.array(intr["sensor"]["pose"]["translation"][0])
    worst = 0.0
    for row in rows:
        k, l, u, v = int(row["k"]), int(row["l"]), float(row["u"]), float(row["v"])
        assert 0 <= k < width and 0 <= l < height
        node = mesh_node(mia, k, l)
        worst = max(worst, float(np.hypot(*(node - (u, v)))))
        j = int(np.argmin(np.hypot(*(points - (u, v)).T)))
        assert np.hypot(*(points[j] - (u, v))) < 0.01
        # The micro-lens of this micro-image: indices reversed; projected from the main lens's
        # centre onto the sensor plane, in the sensor's pixels, then UV.
        lens = mesh_node(mla, width - 1 - k, height - 1 - l)
        hit = lens * (sensor_t[2] / lens[2])
        x, y = (hit[:2] - sensor_t[:2]) / S
        assert np.hypot(W - 1 - x - u, H - 1 - y - v) < 0.01, "micro-lens (%d, %d) projects off its micro-image" % (k, l)
        assert abs(lens[2] + D) < 1e-9
        ck, cl = keys[j]
        ours = ((ck - math.floor(cl / 2)) - cl) % 3
        t_ml = lens_type(width - 1 - k, height - 1 - l)
        assert intr["mla"]["focal_lengths"][t_ml] == FOCAL[ours], (k, l, t_ml, ours)
    assert worst < 0.01, worst
    assert np.hypot(intr["pp"][0][0] - (W - 1) / 2.0, intr["pp"][0][1] - (H - 1) / 2.0) < 1e-9
    # Internal parameters against the thin-lens micro-image radius.
    dc = spacing * S
    assert abs(params["dc"] - dc) < 1e-12 and params["dC"] == PITCH and abs(params["lambda"] - D / (D + D_MLA)) < 1e-12
    assert params["N"] == N and params["I"] == 3 and params["scale"] == S
    mia_types = {}
    for row in rows:
        k, l = int(row["k"]), int(row["l"])
        j = int(np.argmin(np.hypot(*(points - (float(row["u"]), float(row["v"]))).T)))
        ck, cl = keys[j]
        mia_types.setdefault(lens_type(k, l), set()).add(((ck - math.floor(cl / 2)) - cl) % 3)
    for t, q in enumerate(params["q"]):
        assert len(mia_types[t]) == 1
        f = FOCAL[mia_types[t].pop()]
        radius = F * D_MLA / (2 * D * N) + PITCH / 2 * abs(1 - D_MLA / f + D_MLA / D)
        assert abs(abs(params["m"] / N + q) - radius) < 1e-12 and params["m"] / N + q < 0
        assert abs(params["q_prime"][t] - (q + dc / 2)) < 1e-12


def test_bap_observations(exported, args):
    folder, out = exported
    rows = read_rows(os.path.join(out, "obs", "bap.csv"))
    intr = read_js(os.path.join(out, "config", "intrinsics.js"))
    mia = intr["mia"]["mesh"]
    views = read_js(os.path.join(folder, "targets.json"))["views"]
    expected = 0
    for view in views:
        corners = {}
        for row in read_rows(os.path.join(folder, view["points"])):
            corners[(int(row["row"]), int(row["col"]))] = tuple(float(row[c]) for c in "xyz")
        pts = list(corners.items())
        run = subprocess.run([args.project, "--blur", os.path.join(folder, view["image"][:-4] + ".plenoptic.json"), "-"],
                             input="".join("%.17g %.17g %.17g\n" % p for _, p in pts), capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        truth = [line.split() for line in run.stdout.splitlines()]
        expected += len(truth)
        mine = [r for r in rows if int(r["frame"]) == view["view"]]
        assert len(mine) == len(truth), (len(mine), len(truth))
        for words in truth:
            point, k, l, u, v, rho = int(words[0]), int(words[1]), int(words[2]), *map(float, words[3:])
            (crow, ccol), world = pts[point]
            match = [r for r in mine if abs(float(r["u"]) - u) < 1e-9 and abs(float(r["v"]) - v) < 1e-9]
            assert len(match) == 1, (u, v)
            r = match[0]
            assert float(r["rho"]) == rho and int(r["cluster"]) == crow * 7 + ccol
            # libpleno's blur radius from the corner's thin-lens image (camera at the origin, +z).
            z = world[2] * 1000.0
            b = F * z / (z - F)
            vd = (b - D) / D_MLA
            ours = ((k - math.floor(l / 2)) - l) % 3
            assert abs(PITCH / 2 * (D_MLA / FOCAL[ours] + 1 / vd - 1) / S - rho) < 1e-4, (rho, vd)
            node = mesh_node(mia, int(r["k"]), int(r["l"]))
            assert np.hypot(*(node - (u, v))) < PITCH / S, "the corner's image lies in its lens's micro-image"
    assert len(rows) == expected > 50


def test_refusals(args, exported):
    folder, _ = exported
    lone = pt.render(args.povray, os.path.join(args.work, "lone"), "lone",
                     "#version 3.7;\n%s\nplane { z, 0.4 pigment { rgb 1 } finish { emission 1 } }\n" % CAMERA, W, H)
    run = export(args, lone, os.path.join(args.work, "lone_out"))
    assert run.returncode == 2 and "targets.json" in run.stderr, run.stderr
    circles = targets(args, "circles", "circles:4x5:0.001:0.0003")
    run = export(args, os.path.join(circles, "target_000.png"), os.path.join(args.work, "circles_out"))
    assert run.returncode == 2 and "checkerboards" in run.stderr, run.stderr
