# SPDX-License-Identifier: AGPL-3.0-or-later
"""compote: a calibration set of plenoptic-targets renders as COMPOTE / libpleno read a camera's
calibration data (docs/export/compote.md).

RENDER is one view of a plenoptic-targets folder (DIR/targets.json lists its views); every view of
the set is exported, view k as frame k. Written:

  config/camera.js      the camera COMPOTE starts from: mia (the micro-image array: geometry 1,
                        hexagonal rows aligned, width and height in lenses, pitch in pixels, pose
                        in the image), sensor (scale mm/pixel, width, height), main_lens (aperture
                        = f-number, f mm), dist_focus (mm), I (lens types), mode (0 unfocused,
                        1 Keplerian, 2 Galilean)
  config/intrinsics.js  the whole camera as libpleno describes a calibrated one: D, d, I, mode,
                        main_lens (f, aperture, diameter, pose), mla (focal_lengths in libpleno's
                        lens-type order, mesh with pitch mm and 3-D pose), mia, sensor (with pose),
                        pp (principal point), focal_planes, distortions (all zero: a thin lens)
  config/params.js      libpleno's internal parameters: m, q, q_prime (micro-image radius
                        R(1/N) = m / N + q_i), dc, dC, lambda, N, I, scale, kappa
  config/scene.js       the checkerboard: lph (square, mm), x_grid, y_grid (inner corners), pose
  obs/center.csv        k,l,u,v: every micro-image centre in the picture (measured by the render,
                        <stem>.microimages.csv, where it wrote them; else the metadata lattice)
  obs/bap.csv           k,l,u,v,rho,cluster,frame: every image of every checkerboard corner in every
                        view, with its blur radius rho (pixels, plenoptic-project --blur: the
                        render's truth, libpleno's sign), cluster = the corner's index in libpleno's
                        checkerboard (row * x_grid + col), frame = the view

Field lists from COMPOTE's examples/config (camera.js, intrinsics.js, params.js, scene.js) and
examples/obs (bap-*.csv, center-*.csv), and libpleno's definitions: pleno/geometry/mesh.cpp (the
grid's nodes), pleno/geometry/internals.h (the internal parameters), pleno/processing/tools/lens.h
(the lens-type rule), pleno/geometry/camera/camera.cpp and plenoptic.cpp (image UV = W-1-x, H-1-y;
micro-lens and micro-image indices reversed), pleno/processing/precalibration/preprocess.cpp (the
signs of m and q, q' = q + dc/2), learnt by reading them.

Conversions: our pixel centres are at integers, as libpleno's (OpenCV's); libpleno's camera frame
is ours with y reversed (x, -y, z: the main lens at 0, the MLA at z = -D, the sensor at -(D + d)).
Refused: what the raytrix export refuses (the lattice must be exact), circle-grid targets, renders
that are not plenoptic-targets views, views whose cameras differ."""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from . import ExportError, Render
from .lenses import check_camera, lens_types, lenses_in_picture, row_direction

SUMMARY = "COMPOTE / libpleno: camera, intrinsics, params and scene configs, micro-image centre and BAP CSVs"
OPTIONS = {"project": "the plenoptic-project program (default: $PLENOPTIC_PROJECT, the build tree's or the install's)"}

SIN60 = math.sqrt(3.0) / 2.0


def lens_type(types: int, k: int, l: int) -> int:
    """libpleno's lens type of mesh node (k col, l row), hexagonal rows aligned: (l mod (I-1) + k) mod I."""
    if types == 1:
        return 0
    return ((l % (types - 1)) + k) % types


def node(pitch: tuple[float, float], k: np.ndarray, l: np.ndarray) -> np.ndarray:
    """libpleno's GridMesh node (hexagonal rows aligned) in its own frame: (px (k + 0.5 [l even]), py sin60 l)."""
    return np.stack([pitch[0] * (k + 0.5 * (np.mod(l, 2) == 0)), pitch[1] * l * SIN60], axis=-1)


def _translation(rotation: np.ndarray, local: np.ndarray, world: np.ndarray, what: str,
                 tolerance: float) -> np.ndarray:
    """t of world = rotation local + t (the mean over the nodes); ExportError when a node is more
    than tolerance off."""
    t = np.mean(world - local @ rotation.T, axis=0)
    residual = float(np.max(np.abs(local @ rotation.T + t - world)))
    if residual > tolerance:
        raise ExportError("compote: the %s is not a rotated hexagonal grid (a node %.3g off)" % (what, residual))
    return t


def mia_mesh(render: Render) -> dict[str, Any]:
    """The micro-image array as libpleno's mesh: every lens whose centre lies within a diameter of
    the picture gets (k, l) >= 0; height even (so that the micro-lens indices, reversed, keep
    libpleno's row parity)."""
    meta = render.meta
    row_vector, _ = row_direction(render)
    spacing = float(np.hypot(*row_vector))
    phi = math.atan2(float(row_vector[1]), float(row_vector[0]))  # in (u, v), v down
    rot = np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])
    ks, l, u, v = meta.all_centres(margin=-spacing)
    ks = ks.astype(np.int64)
    l = l.astype(np.int64)
    centres = np.stack([u, v], axis=-1)
    ref = int(np.argmin(np.hypot(u - meta.width / 2.0, v - meta.height / 2.0)))
    local = (centres - centres[ref]) @ rot  # rot^T (c - c_ref), row vectors
    rows = np.round(local[:, 1] / (spacing * SIN60)).astype(np.int64)
    # Reference lens at (0, 0) of an even row: its x is spacing * 0.5.
    cols = np.round((local[:, 0] + 0.5 * spacing) / spacing - 0.5 * (np.mod(rows, 2) == 0)).astype(np.int64)
    rows -= rows.min() - (rows.min() % 2)  # shift by an even number: min row 0 or 1
    cols -= cols.min()
    height = int(rows.max()) + 1
    height += height % 2
    width = int(cols.max()) + 1
    t = _translation(rot, node((spacing, spacing), cols, rows), centres, "micro-image array", 1e-6 * spacing)
    pitch, rotation = spacing, rot
    return {"ks": ks, "l": l, "k_mi": cols, "l_mi": rows, "width": width, "height": height, "pitch_px": pitch,
            "rotation": rotation, "translation": t, "centres": centres}


def _dist_focus_mm(meta: Any) -> float | None:
    """The distance (mm, from the main lens) the camera is focused at: the scene's focus_distance,
    else the thin-lens object of the array's plane; None when that lies at or beyond infinity."""
    focus = meta.raw["main_lens"].get("focus_distance")
    if isinstance(focus, (int, float)):
        return float(focus) * meta.mm_per_unit
    f, big_d = meta.focal_length_mm, meta.main_distance_mm
    return f * big_d / (big_d - f) if big_d > f else None


def camera_numbers(render: Render) -> dict[str, Any]:
    """Every number of the configuration files, and the lens maps the observations use."""
    meta = render.meta
    check_camera(render, "compote")
    if meta.main_lens_type != "thin_lens":
        raise ExportError("compote: libpleno's main lens is a thin lens; the render's is %s" % meta.main_lens_type)
    if any(abs(float(x)) > 0 for x in meta.raw["microlens_array"]["rotate_deg"][:2]):
        raise ExportError("compote: the array is tilted")
    lenses_in_picture(render, "compote")  # refuses measured centres off the lattice
    focal = lens_types(render)
    types = len(focal)
    d, big_d, s = meta.array_distance_mm, meta.main_distance_mm, float(meta.pixel_size_mm[0])
    big_f = float(meta.focal_length_mm or math.nan)
    if all(f > d for f in focal):
        mode = 2
    elif all(f < d for f in focal):
        mode = 1
    elif all(f == d for f in focal):
        mode = 0
    else:
        raise ExportError("compote: some lens types focus in front of the sensor and some behind (d = %g mm, f = %s): "
                          "libpleno's camera has one mode" % (d, ", ".join("%g" % f for f in focal)))
    mia = mia_mesh(render)
    width, height = mia["width"], mia["height"]
    # Our type of each mesh node, and libpleno's types of the micro-image and micro-lens indices.
    ours = np.mod(mia["ks"] - mia["l"], 3) if types == 3 else np.zeros_like(mia["ks"])
    k_ml, l_ml = width - 1 - mia["k_mi"], height - 1 - mia["l_mi"]
    mla_order = _type_map(types, ours, k_ml, l_ml, "micro-lens")
    mia_order = _type_map(types, ours, mia["k_mi"], mia["l_mi"], "micro-image")
    # The micro-lens centres in libpleno's camera frame (x, -y, z), from the array's lattice.
    p = meta.pitch_mm
    theta = math.radians(float(meta.raw["microlens_array"]["rotate_deg"][2]))
    tx, ty, tz = (float(x) for x in meta.raw["microlens_array"]["translate_mm"])
    row_k = mia["ks"] + np.floor_divide(mia["l"], 2)
    x0, y0 = (row_k + np.mod(mia["l"], 2) / 2.0) * p, mia["l"] * p * SIN60
    x = math.cos(theta) * x0 - math.sin(theta) * y0 + tx
    y = math.sin(theta) * x0 + math.cos(theta) * y0 + ty
    z = np.full_like(x, -meta.raw["main_lens"]["distance_mm"] + tz)
    lens_world = np.stack([x, -y, z], axis=-1)
    # The array turned by theta about z in our frame is turned by -theta in libpleno's (y reversed);
    # libpleno's micro-lens rows run along +x with even rows shifted by +p/2. Of the six lattice
    # directions, the one within 30 degrees of +x gives the mesh's rotation.
    angle = -theta
    angle = (angle + math.pi / 6) % (math.pi / 3) - math.pi / 6
    r3 = np.array([[math.cos(angle), -math.sin(angle), 0.0], [math.sin(angle), math.cos(angle), 0.0], [0.0, 0.0, 1.0]])
    if abs(angle) < 1e-15:
        r3 = np.eye(3)
    local = np.hstack([node((p, p), k_ml, l_ml), np.zeros((len(k_ml), 1))])
    t3 = _translation(r3, local, lens_world, "micro-lens array", 1e-9)
    ox, oy = (float(w) for w in meta.raw["sensor"]["offset_mm"])
    sensor_t = np.array([ox - s * (meta.width - 1) / 2.0, -oy - s * (meta.height - 1) / 2.0, -(big_d + d)])
    # Check: every micro-lens centre projected from the main lens's centre onto the sensor lands on
    # its micro-image node (libpleno's uv), as our lattice has it.
    hit = lens_world * (sensor_t[2] / lens_world[:, 2:3])
    uv = np.stack([meta.width - 1 - (hit[:, 0] - sensor_t[0]) / s, meta.height - 1 - (hit[:, 1] - sensor_t[1]) / s],
                  axis=-1)
    worst = float(np.max(np.hypot(*(uv - mia["centres"]).T)))
    if worst > 1e-6:
        raise ExportError("compote: the micro-lens array and sensor poses put a micro-image %.3g px off" % worst)
    aperture = float(meta.aperture_mm or math.nan)
    f_number = big_f / aperture
    sign = 1.0 if mode == 1 else -1.0  # preprocess.cpp: radii are negated except for Keplerian cameras
    dc = mia["pitch_px"] * s
    q = [sign * (p / 2.0) * abs(1.0 - d / f + d / big_d) for f in focal]
    principal = (meta.width - 1 + sensor_t[0] / s, meta.height - 1 + sensor_t[1] / s)
    focal_planes: list[float | None] = []
    for f in focal:
        if f == d:
            focal_planes.append(None)
            continue
        b = big_d + f / (f - d) * d  # the image the type focuses, from the main lens
        focal_planes.append(big_f * b / (b - big_f) if b > big_f else None)
    return {"mode": mode, "I": types, "D": big_d, "d": d, "F": big_f, "N": f_number, "aperture_mm": aperture,
            "dist_focus": _dist_focus_mm(meta), "scale": s, "mia": mia, "mla_rotation": r3, "mla_translation": t3,
            "mla_focal_lengths": [focal[mla_order[t]] for t in range(types)], "pitch_mm": p,
            "sensor_translation": sensor_t, "pp": principal,
            "m": sign * big_f * d / (2.0 * big_d), "q": [q[mia_order[t]] for t in range(types)], "dc": dc,
            "dC": p, "lambda": p / dc, "focal_planes": [focal_planes[mla_order[t]] for t in range(types)],
            "kappa": math.sqrt(5.0 / 18.0)}


def _type_map(types: int, ours: np.ndarray, k: np.ndarray, l: np.ndarray, what: str) -> list[int]:
    """[our type of libpleno's type t for t in range(types)]; ExportError when the two rules are not
    one relabelling of each other."""
    theirs = np.array([lens_type(types, int(a), int(b)) for a, b in zip(k, l)])
    mapping = []
    for t in range(types):
        mine = set(ours[theirs == t].tolist())
        if len(mine) != 1:
            raise ExportError("compote: libpleno's %s type %d covers our lens types %s" % (what, t, sorted(mine)))
        mapping.append(mine.pop())
    return mapping


def _pose(rotation: np.ndarray, translation: np.ndarray) -> dict[str, Any]:
    return {"rotation": [[float(x) + 0.0 for x in row] for row in rotation], "translation": [[float(x) for x in translation]]}


def _mia_json(n: dict[str, Any]) -> dict[str, Any]:
    mia = n["mia"]
    return {"mesh": {"geometry": 1, "width": mia["width"], "height": mia["height"],
                     "pitch": [[mia["pitch_px"], mia["pitch_px"]]], "pose": _pose(mia["rotation"], mia["translation"])}}


def config_files(n: dict[str, Any], target: dict[str, Any], mm_per_unit: float) -> dict[str, Any]:
    sensor = {"scale": n["scale"], "width": None, "height": None}
    return {
        "camera": {"mia": _mia_json(n), "sensor": sensor,
                   "main_lens": {"aperture": n["N"], "f": n["F"]}, "dist_focus": n["dist_focus"], "I": n["I"],
                   "mode": n["mode"]},
        "intrinsics": {
            "D": n["D"], "d": n["d"], "I": n["I"], "mode": n["mode"], "dist_focus": n["dist_focus"],
            "main_lens": {"f": n["F"], "aperture": n["N"], "diameter": n["aperture_mm"],
                          "pose": _pose(np.eye(3), np.zeros(3))},
            "mla": {"focal_lengths": n["mla_focal_lengths"],
                    "mesh": {"geometry": 1, "width": n["mia"]["width"], "height": n["mia"]["height"],
                             "pitch": [[n["pitch_mm"], n["pitch_mm"]]],
                             "pose": _pose(n["mla_rotation"], n["mla_translation"])}},
            "mia": _mia_json(n),
            "sensor": dict(sensor, pose=_pose(np.eye(3), n["sensor_translation"])),
            "pp": [[float(n["pp"][0]), float(n["pp"][1])]],
            "focal_planes": n["focal_planes"],
            "distortions": {"model": 0, "radial": [[0.0, 0.0, 0.0]], "tangential": [[0.0, 0.0]],
                            "depth": [[0.0, 0.0, 0.0]]},
        },
        "params": {"m": n["m"], "scale": n["scale"], "q": n["q"], "q_prime": [q + n["dc"] / 2.0 for q in n["q"]],
                   "dc": n["dc"], "dC": n["dC"], "N": n["N"], "I": n["I"], "kappa": n["kappa"], "lambda": n["lambda"]},
        "scene": {"checkerboards": [{"lph": target["square"] * mm_per_unit, "x_grid": target["cols"] - 1,
                                     "y_grid": target["rows"] - 1, "pose": _pose(np.eye(3), np.zeros(3))}]},
    }


def _views(render: Render) -> tuple[dict[str, Any], str]:
    folder = os.path.dirname(os.path.abspath(render.image_path))
    path = os.path.join(folder, "targets.json")
    if not os.path.exists(path):
        raise ExportError("compote: %s is not a plenoptic-targets view (no targets.json beside it): COMPOTE's "
                          "observations are a calibration target's corners" % render.image_path)
    with open(path, encoding="utf-8") as f:
        targets = json.load(f)
    if targets.get("target", {}).get("kind") != "checkerboard":
        raise ExportError("compote: the target set is of %s; COMPOTE's scene takes checkerboards"
                          % targets.get("target", {}).get("kind"))
    names = [v["image"] for v in targets["views"]]
    if os.path.basename(render.image_path) not in names:
        raise ExportError("compote: %s is not one of the views targets.json lists" % render.image_path)
    return targets, folder


def export(render: Render, out_dir: Path, **options: Any) -> list[Path]:
    from ..metadata import load_metadata
    from ..projection import project_points
    meta = render.meta
    from ..locate import find_project
    targets, folder = _views(render)
    try:
        tool = find_project(options.get("project") or os.environ.get("PLENOPTIC_PROJECT"))
    except FileNotFoundError:
        raise ExportError("compote: the blur radii come from plenoptic-project, which was not found: give its path "
                          "with -O project=PATH")
    n = camera_numbers(render)
    files = config_files(n, targets["target"], meta.mm_per_unit)
    for name in ("camera", "intrinsics"):
        files[name]["sensor"]["width"] = meta.width
        files[name]["sensor"]["height"] = meta.height
    out = Path(out_dir)
    (out / "config").mkdir()
    (out / "obs").mkdir()
    written = []
    for name, doc in files.items():
        path = out / "config" / (name + ".js")
        path.write_text(json.dumps(doc, indent=4) + "\n", encoding="utf-8")
        written.append(path)
    mia = n["mia"]
    index = {(int(a), int(b)): (int(k), int(l)) for a, b, k, l in zip(mia["ks"], mia["l"], mia["k_mi"], mia["l_mi"])}
    lenses = lenses_in_picture(render, "compote")
    centre_path = out / "obs" / "center.csv"
    with open(centre_path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["k", "l", "u", "v"])
        for ks, l, u, v in zip(lenses.ks, lenses.l, lenses.mu, lenses.mv):
            if math.isfinite(u) and math.isfinite(v):
                w.writerow([*index[(int(ks), int(l))], repr(float(u)), repr(float(v))])
    written.append(centre_path)
    x_grid = targets["target"]["cols"] - 1
    bap_path = out / "obs" / "bap.csv"
    dropped = 0
    with open(bap_path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["k", "l", "u", "v", "rho", "cluster", "frame"])
        for view in targets["views"]:
            view_meta_path = os.path.join(folder, os.path.splitext(view["image"])[0] + ".plenoptic.json")
            view_meta = load_metadata(view_meta_path, (meta.width, meta.height))
            if (not np.allclose(view_meta.origin, meta.origin, atol=1e-9) or not np.allclose(view_meta.a, meta.a, atol=1e-9)
                    or not np.allclose(view_meta.b, meta.b, atol=1e-9)):
                raise ExportError("compote: view %s has another camera than %s" % (view["image"], render.image_path))
            corners: list[tuple[tuple[int, int], tuple[float, float, float]]] = []
            with open(os.path.join(folder, view["points"]), encoding="utf-8") as pf:
                for row in csv.DictReader(pf):
                    key = (int(row["row"]), int(row["col"]))
                    if not corners or corners[-1][0] != key:
                        corners.append((key, (float(row["x"]), float(row["y"]), float(row["z"]))))
            if not corners:
                continue
            try:
                hits = project_points(view_meta_path, [c[1] for c in corners], tool=tool, blur=True)
            except (OSError, RuntimeError) as e:
                raise ExportError("compote: plenoptic-project (%s) failed on %s: %s" % (tool, view_meta_path, e))
            for point, k, l, u, v, rho in hits:
                ks = int(k) - (int(l) // 2)
                if (ks, int(l)) not in index:
                    dropped += 1  # a lens whose centre lies over a diameter outside the picture
                    continue
                (corner_row, corner_col), _ = corners[int(point)]
                w.writerow([*index[(ks, int(l))], repr(float(u)), repr(float(v)), repr(float(rho)),
                            corner_row * x_grid + corner_col, view["view"]])
    written.append(bap_path)
    render.progress.stage("compote: %d views, mesh %d x %d, %d lens type%s%s" % (
        len(targets["views"]), mia["width"], mia["height"], n["I"], "" if n["I"] == 1 else "s",
        ", %d corner images through lenses outside the mesh left out" % dropped if dropped else ""))
    return written
