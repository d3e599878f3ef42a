# SPDX-License-Identifier: AGPL-3.0-or-later
"""raytrix: the render as PlenopticToolbox 2.0 (Kiel) reads a Raytrix camera's image
(docs/export/raytrix.md).

<stem>.xml   the RayCalibData calibration: microimage offset, diameter, rotation, lens border,
             lens base vectors, sub-grid base, total covering plane and one lens_type per
             microlens type with its virtual-depth range. The field list and their meaning are
             those of PlenopticToolbox 2.0's reader (python/plenopticIO/imgIO.py,
             read_calibration and MLACalibration; python/plenopticIO/lens_grid.py, hex_lens_grid,
             which places the lenses; its lens types by _hex_focal_type), learnt by reading it.
<stem>.png   the rendered picture beside it, as the toolbox pairs them (load_scene: the .xml's
             name with .png).
<stem>_disp.png, <stem>_disp.pfm
             with the render's virtual depth map: the disparity the toolbox compares its estimate
             with (load_with_disp reads <stem>_disp.png, three equal channels): disparity =
             diameter / v pixels. The PNG holds it divided by the diameter (that is 1/v, in [0, 1]
             for v >= 1; 0 where there is none), 16 bits, as the toolbox's reader (matplotlib's
             imread) returns a PNG's values in [0, 1]; the PFM holds the disparity in pixels as
             float32, NaN where there is none.

Conversions (ours -> the toolbox's): pixel centres are at integers in both; the toolbox's image
centre is ((W - 1) / 2, (H - 1) / 2); its offset is the centre lens's position from it with y UP
(MLACalibration takes the row as -y); its rotation (radians) turns the lattice counter-clockwise
as the image is displayed (v down); its diameter is the lens spacing in pixels. Virtual depths are
ours (v = -a / d, positive behind the array), which are Raytrix's positive virtual depths.

Refused: a rectangular grid, a tilted array, non-square pixels, a prescription or a distorted thin
main lens, and arrays whose measured microimage centres leave the lattice by more than 0.01 px
(manufacturing errors): the XML's one lattice cannot express them."""

from __future__ import annotations

import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from . import ExportError, Render
from .lenses import (check_camera, image_centre, lens_types, lenses_in_picture, row_direction,
                     virtual_depth_in_focus, write_png16)

SUMMARY = "PlenopticToolbox 2.0's Raytrix pair: RayCalibData .xml beside the .png, and a disparity image"
OPTIONS = {
    "blur_px": "the blur radius (pixels) within which a lens type counts as sharp, for its virtual-depth "
               "range (default 1)",
    "max_virtual_depth": "the depth_range max written where a lens type is sharp to infinity (default 100)",
}

SQRT3 = math.sqrt(3.0)


def _number(value: Any, name: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ExportError("-O %s must be a positive number, found %r" % (name, value))
    if not (math.isfinite(number) and number > 0):
        raise ExportError("-O %s must be a positive number, found %r" % (name, value))
    return number


def depth_range(f_mm: float, d_mm: float, pitch_mm: float, pixel_mm: float, blur_px: float,
                cap: float) -> tuple[float, float] | None:
    """The virtual depths v >= 1 at which a lens of focal length f blurs a point by at most
    blur_px pixels: |(A/2)(d/f + 1/v - 1)| <= blur_px * pixel, A the pitch (libpleno's blur
    model, docs/ground-truth.md '--blur'); 1/v then lies in [c - e, c + e], c = 1 - d/f,
    e = 2 blur_px pixel / A. None when no v >= 1 qualifies; the upper end is `cap` when the range
    reaches infinity (1/v down to 0 or below)."""
    c = 1.0 - d_mm / f_mm
    e = 2.0 * blur_px * pixel_mm / pitch_mm
    low, high = c - e, min(c + e, 1.0)  # bounds on 1/v; v >= 1 means 1/v <= 1
    if high <= 0 or low > high:
        return None
    v_min = 1.0 / high
    v_max = cap if low <= 0 else 1.0 / low
    return v_min, v_max


def total_covering_plane(render: Render, types: int) -> float:
    """The virtual depth from which every point is seen by a lens of each type: the cone from the
    exit pupil (diameter A at distance D from the array) to an image point a behind the array has
    radius (A/2) a / (D + a) in the array's plane; it must reach the circumradius of the lattice of
    one type, p / sqrt(3) for one type and p for three. inf when the cone never does."""
    meta = render.meta
    reach = meta.pitch_mm / SQRT3 if types == 1 else meta.pitch_mm
    k = 2.0 * reach / float(meta.exit_pupil_mm or math.nan)
    if k >= 1:
        return math.inf
    return meta.pupil_distance_mm * k / (1.0 - k) / meta.array_distance_mm


def reader_axial(render: Render, du: np.ndarray, dv: np.ndarray, diameter: float,
                 angle: float) -> tuple[np.ndarray, np.ndarray]:
    """The toolbox's axial coordinates (along its basis lby, then lbx) of lenses at pixel offsets
    (du, dv) from its centre lens: lbx is the right neighbour, lby the lower-right one (v down), in
    the grid before its rotation by `angle` counter-clockwise on the screen."""
    c, s = math.cos(angle), math.sin(angle)
    # Undo the rotation: the toolbox turns (row, col) by [[c, -s], [s, c]].
    row, col = dv, du
    row0, col0 = c * row + s * col, -s * row + c * col
    # Unrotated: lbx = (0, 1) and lby = (sqrt(3)/2, 1/2) in (row, col), times the diameter.
    alpha = row0 / (diameter * SQRT3 / 2.0)
    beta = col0 / diameter - alpha / 2.0
    return np.round(alpha).astype(np.int64), np.round(beta).astype(np.int64)


def hex_focal_type(alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """The toolbox's 3-colouring of its axial coordinates (_hex_focal_type): ((-alpha mod 3) + beta) mod 3."""
    return np.mod(np.mod(-alpha, 3) + beta, 3)


def calibration(render: Render, blur_px: float = 1.0, cap: float = 100.0, fmt: str = "raytrix",
                require_lattice: bool = True) -> dict[str, Any]:
    """Every number of the XML, and the lenses it places (for the checks and the kiel format):
    the lattice's lenses; require_lattice refuses measured centres off it (lenses_in_picture)."""
    meta = render.meta
    check_camera(render, fmt)
    lenses = lenses_in_picture(render, fmt, require_lattice)
    if len(lenses.ks) == 0:
        raise ExportError("raytrix: no microimage centre lies in the picture")
    row_vector, angle = row_direction(render)
    diameter = float(np.hypot(*row_vector))
    centre = image_centre(render)
    nearest = int(np.argmin(np.hypot(lenses.u - centre[0], lenses.v - centre[1])))
    c0 = np.array([lenses.u[nearest], lenses.v[nearest]])
    alpha, beta = reader_axial(render, lenses.u - c0[0], lenses.v - c0[1], diameter, angle)
    # The lattice the XML describes must put every lens where ours does (it is exact for a regular
    # hexagonal lattice; this guards the conversion itself).
    predicted = predict_centres(c0 - centre, diameter, angle, alpha, beta, centre)
    worst = float(np.max(np.hypot(predicted[0] - lenses.u, predicted[1] - lenses.v)))
    if worst > 1e-6:
        raise ExportError("raytrix: the XML's lattice would put a lens %.3g px from our lattice" % worst)
    focal = lens_types(render)
    d = meta.array_distance_mm
    pixel = float(meta.pixel_size_mm[0])
    types: list[dict[str, Any]] = []
    reader_type = hex_focal_type(alpha, beta)
    for t, f in enumerate(focal):
        if not f > d:
            raise ExportError("raytrix: lens type %d has f = %g mm <= d = %g mm: the XML describes focused "
                              "plenoptic cameras, whose depth ranges are positive virtual depths (Raytrix's "
                              "Galilean arrangement, d < f for every type); a plenoptic 1.0 camera (d = f) is "
                              "decoded into views instead (--to views or eslf)" % (t, f, d))
        members = np.nonzero(lenses.type == t)[0]
        colours = set(reader_type[members].tolist())
        # One lens type: the toolbox's rule is not consulted (every lens is type 0).
        if len(focal) > 1 and len(colours) != 1:
            raise ExportError("raytrix: lens type %d does not map onto one colour of the toolbox's hexagonal "
                              "lens-type rule" % t)
        # The offset of the type: the axial coordinates of its lens nearest the centre lens.
        m = members[np.argmin(np.hypot(lenses.u[members] - c0[0], lenses.v[members] - c0[1]))]
        rng = depth_range(f, d, meta.pitch_mm, pixel, blur_px, cap)
        if rng is None:
            raise ExportError("raytrix: lens type %d (f = %g mm, d = %g mm) is sharp at no virtual depth of at least "
                              "1 within %g px of blur: the XML's depth ranges are positive virtual depths (Raytrix's "
                              "Galilean arrangement, d < f)" % (t, f, d, blur_px))
        types.append({"id": t, "offset": (int(alpha[m]), int(beta[m])), "depth_range": rng, "focal_length_mm": f,
                      "virtual_depth_in_focus": virtual_depth_in_focus(f, d)})
    if len({hex_focal_type(np.array([o["offset"][0]]), np.array([o["offset"][1]]))[0] for o in types}) != len(types):
        raise ExportError("raytrix: two lens types share a colour of the toolbox's lens-type rule")
    if meta.diameter_px is None:
        raise ExportError("raytrix: the metadata has no microimage diameter (microimage_lattice.microimage_diameter_px)")
    border = max(0.0, (diameter - float(meta.diameter_px)) / 2.0)
    offset = c0 - centre
    return {"offset_xy": (float(offset[0]) + 0.0, float(-offset[1]) + 0.0), "diameter": diameter, "rotation": angle,
            "lens_border": border, "tcp": total_covering_plane(render, len(focal)),
            "sub_grid_base": (3.0, SQRT3) if len(focal) == 3 else (1.0, SQRT3), "lens_types": types,
            "lenses": lenses, "axial": (alpha, beta), "centre_lens": c0}


def predict_centres(offset_uv: np.ndarray, diameter: float, angle: float, alpha: np.ndarray, beta: np.ndarray,
                    centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the toolbox puts the lens of axial (alpha, beta): image centre + offset +
    R(angle) (alpha lby + beta lbx) diameter, in (u, v)."""
    row0 = alpha * diameter * SQRT3 / 2.0
    col0 = (alpha / 2.0 + beta) * diameter
    c, s = math.cos(angle), math.sin(angle)
    row = c * row0 - s * col0
    col = s * row0 + c * col0
    return centre[0] + offset_uv[0] + col, centre[1] + offset_uv[1] + row


def _f(x: float) -> str:
    return repr(float(x))


def xml_text(cal: dict[str, Any]) -> str:
    ox, oy = cal["offset_xy"]
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             "<!-- Written by plenoptic-export (povray-plenoptic). The fields PlenopticToolbox 2.0 reads; "
             "docs/export/raytrix.md. -->",
             '<RayCalibData version="1.0">',
             '  <offset units="pix">', "    <x>%s</x>" % _f(ox), "    <y>%s</y>" % _f(oy), "  </offset>",
             '  <diameter units="pix">%s</diameter>' % _f(cal["diameter"]),
             '  <rotation units="rad">%s</rotation>' % _f(cal["rotation"]),
             '  <lens_border units="pix">%s</lens_border>' % _f(cal["lens_border"])]
    if math.isfinite(cal["tcp"]):
        lines.append('  <tcp units="virtual_depth">%s</tcp>' % _f(cal["tcp"]))
    lines += ['  <lens_base_x units="lens">', "    <x>1.0</x>", "    <y>0.0</y>", "  </lens_base_x>",
              '  <lens_base_y units="lens">', "    <x>0.5</x>", "    <y>%s</y>" % _f(SQRT3 / 2.0), "  </lens_base_y>",
              '  <sub_grid_base units="lens">', "    <x>%s</x>" % _f(cal["sub_grid_base"][0]),
              "    <y>%s</y>" % _f(cal["sub_grid_base"][1]), "  </sub_grid_base>",
              '  <distortion type="radial">', "    <function>constant</function>", '    <parameter count="0">0</parameter>',
              '    <offset units="pix">', "      <x>0.0</x>", "      <y>0.0</y>", "    </offset>", "  </distortion>"]
    for t in cal["lens_types"]:
        lines += ['  <lens_type id="%d">' % t["id"], '    <offset units="lens">', "      <x>%d</x>" % t["offset"][0],
                  "      <y>%d</y>" % t["offset"][1], "    </offset>", '    <depth_range units="virtual_depth">',
                  "      <min>%s</min>" % _f(t["depth_range"][0]), "      <max>%s</max>" % _f(t["depth_range"][1]),
                  "    </depth_range>", "  </lens_type>"]
    lines.append("</RayCalibData>")
    return "\n".join(lines) + "\n"


def copy_picture(render: Render, out: Path) -> Path:
    """<stem>.png: the render's PNG as it is (the toolbox reads a colour .png or .bmp)."""
    if render.info.file_format != "png":
        raise ExportError("raytrix: PlenopticToolbox 2.0 pairs the XML with a .png or .bmp, and the render is %s; "
                          "render to PNG" % render.info.file_format)
    target = out / (render.stem + ".png")
    shutil.copyfile(render.image_path, target)
    return target


def disparity_images(render: Render, out: Path, diameter: float) -> list[Path]:
    """<stem>_disp.png (16-bit, three equal channels, 1/v clipped to [0, 1], 0 where there is no
    positive virtual depth) and <stem>_disp.pfm (diameter / v pixels, NaN where none), from the
    render's virtual depth map; nothing when it wrote none."""
    from ..hci import write_pfm
    from ..images import read_depth_map
    path = render.meta.sidecar_path("virtual_depth_map")
    if path is None:
        return []
    v = read_depth_map(path)
    if v is None or v.shape != (render.meta.height, render.meta.width):
        raise ExportError("raytrix: cannot read the virtual depth map %s as a %d x %d image"
                          % (path, render.meta.width, render.meta.height))
    v = v.astype(np.float64)
    positive = np.isfinite(v) & (v > 0)
    inverse = np.zeros_like(v)
    inverse[positive] = 1.0 / v[positive]
    stored = np.where(inverse <= 1.0, inverse, 0.0)
    level = np.floor(stored * 65535.0 + 0.5).astype(np.uint16)
    png = out / (render.stem + "_disp.png")
    write_png16(png, np.repeat(level[:, :, None], 3, axis=2))
    pfm = out / (render.stem + "_disp.pfm")
    disparity = np.full(v.shape, np.nan)
    disparity[positive] = diameter / v[positive]
    write_pfm(str(pfm), disparity)
    return [png, pfm]


def export(render: Render, out_dir: Path, **options: Any) -> list[Path]:
    blur_px = _number(options.get("blur_px", 1.0), "blur_px")
    cap = _number(options.get("max_virtual_depth", 100.0), "max_virtual_depth")
    cal = calibration(render, blur_px, cap)
    out = Path(out_dir)
    xml = out / (render.stem + ".xml")
    xml.write_text(xml_text(cal), encoding="utf-8")
    written = [xml, copy_picture(render, out)]
    written += disparity_images(render, out, cal["diameter"])
    render.progress.stage("raytrix: %d lenses, diameter %.4f px, rotation %.6g rad, %d lens type%s"
                          % (len(cal["lenses"].ks), cal["diameter"], cal["rotation"], len(cal["lens_types"]),
                             "" if len(cal["lens_types"]) == 1 else "s"))
    return written
