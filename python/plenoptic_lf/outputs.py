# SPDX-License-Identifier: AGPL-3.0-or-later
"""The decoder's output folder: views, mosaic, refocus sweep, EPI, contact sheet, the light field
as .npy and its description as JSON (docs/ground-truth.md lists the files)."""

from __future__ import annotations

import json
import math
import os
import sys
from typing import Sequence

import numpy as np

from .contact_sheet import contact_sheet
from .focus import pick_epi_row, pick_near_far, sharpest_slope_map
from .images import save_png, scaled_pil_image, to_8bit
from .lightfield import LightField
from .progress import Progress


def _mosaic_8bit(lf, gap=2):
    """lightfield.mosaic(lf) as 8-bit sRGB, converted view by view: a quarter of the light field's
    memory instead of several times it."""
    T, S, n_v, n_u, C = lf.data.shape
    out = np.zeros((n_v * (T + gap) - gap, n_u * (S + gap) - gap, C), np.uint8)
    for iv in range(n_v):
        for iu in range(n_u):
            if lf.mask[iv, iu]:
                out[iv * (T + gap):iv * (T + gap) + T, iu * (S + gap):iu * (S + gap) + S] = to_8bit(lf.view(iv, iu))
    return out


def write_outputs(raw: np.ndarray, lf: LightField, outdir: str, slopes: Sequence[float] | np.ndarray, gif: bool = True,
                  npy: bool = True, progress: Progress | None = None, title: str = "") -> str:
    """Writes views, mosaic, refocus sweep (+ GIF), EPI, contact sheet and a JSON description.
    Returns the path of the contact sheet."""
    from PIL import Image
    if progress is None:
        progress = Progress(False)
    os.makedirs(os.path.join(outdir, "views"), exist_ok=True)
    os.makedirs(os.path.join(outdir, "refocus"), exist_ok=True)
    T, S, n_v, n_u, _ = lf.shape
    aspect = lf.display_aspect()

    progress.stage("writing %d sub-aperture views" % int(lf.mask.sum()))
    view_names = []
    for iv in range(n_v):
        for iu in range(n_u):
            if lf.mask[iv, iu]:
                name = "view_v%+03d_u%+03d.png" % (int(round(lf.dv[iv] / lf.step)), int(round(lf.du[iu] / lf.step)))
                save_png(os.path.join(outdir, "views", name), lf.view(iv, iu))
                view_names.append(name)
    Image.fromarray(_mosaic_8bit(lf)).save(os.path.join(outdir, "views_mosaic.png"))

    progress.stage("refocusing at %d slopes" % len(slopes))
    refocused = []
    gif_frames = []
    for i, slope in enumerate(slopes):
        image = lf.refocus(slope)
        refocused.append(image)
        save_png(os.path.join(outdir, "refocus", "refocus_%02d_slope%+.4f.png" % (i, slope)), image)
        gif_frames.append(scaled_pil_image(image, 4 * S, None, aspect))
        progress.update(i + 1, len(slopes))
    if gif and len(gif_frames) > 1:
        try:
            back_and_forth = gif_frames + gif_frames[-2:0:-1]
            back_and_forth[0].save(os.path.join(outdir, "refocus.gif"), save_all=True,
                                   append_images=back_and_forth[1:], duration=180, loop=0)
        except (OSError, ValueError) as e:  # Pillow without GIF support: the PNGs are there
            print("plenoptic-decode: no GIF written (%s)" % e, file=sys.stderr)

    progress.stage("drawing the EPI and the contact sheet")
    best, strength = sharpest_slope_map(refocused)
    near, far = pick_near_far(slopes, best, strength)
    epi_row = pick_epi_row(lf, best, strength)
    cv, _ = lf.centre_index()
    epi, epi_u = lf.epi(epi_row, cv)
    Image.fromarray(to_8bit(epi)).resize((S * 8, len(epi_u) * 16), Image.NEAREST).save(os.path.join(outdir, "epi.png"))
    sheet = contact_sheet(raw, lf, slopes, refocused, near, far, epi_row, title)
    sheet_path = os.path.join(outdir, "contact_sheet.png")
    sheet.save(sheet_path)

    if npy:
        np.save(os.path.join(outdir, "lightfield.npy"), lf.data)
    description = {
        "array": "lightfield.npy" if npy else None,
        "axes": "L[t, s, v, u, c]: lens row, lens column, angular row, angular column, colour (linear RGB)",
        "shape": list(lf.shape),
        "du_px": lf.du.tolist(),
        "dv_px": lf.dv.tolist(),
        "usable_mask": lf.mask.astype(int).tolist(),
        "grid_s_vector_px": lf.A.tolist(),
        "grid_t_vector_px": lf.R.tolist(),
        "grid_origin_index": [float(lf.origin_st[0]), float(lf.origin_st[1])],
        "grid_position_rule": "raw pixel of data[t, s] = microimage_lattice.origin_px + (s0 + s) A + (t0 + t) R",
        "microimage_centres": ("the metadata's microimage_lattice" if lf.meta.lattice_is_exact else
                               "measured, per lens (%s); the lattice fit for lenses it does not list"
                               % lf.meta.microimages.file),
        "dark_mask": lf.dark.astype(int).tolist(),
        "slopes": [float(s) for s in slopes],
        "slope_unit": "lenses along s per angular step (0 = plane imaged onto the array)",
        "slope_distances": [z if z is None or math.isfinite(z) else None
                            for z in (lf.slope_to_distance(s) for s in slopes)],
        "near_far_slope_index": [near, far],
        "views": view_names,
        "epi_lens_row": epi_row,
    }
    with open(os.path.join(outdir, "lightfield.json"), "w") as f:
        json.dump(description, f, indent=1)
    return sheet_path
