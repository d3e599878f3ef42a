# SPDX-License-Identifier: AGPL-3.0-or-later
"""The contact sheet: one labelled picture that shows the plenoptic effect."""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Sequence

import numpy as np

from .images import scaled_pil_image, to_8bit
from .metadata import Metadata
from .microimages import measured_centres, microimage_centre

if TYPE_CHECKING:
    from PIL import Image

    from .lightfield import LightField


def _main_lens_phrase(meta):
    """What is in front of the array: 'behind a traced prescription (lens.dat)', 'behind a thin
    main lens (f = 50 mm, f/2)', ..."""
    lens = meta.main_lens
    kind = meta.main_lens_type
    if kind in ("prescription", "thick_lens"):
        source = (lens.lens_file if lens.lens_file else
                  "an inline prescription of %d surfaces" % lens.surface_count if lens.surface_count is not None else
                  "an inline prescription")
        if kind == "prescription":
            return "behind a traced prescription (%s)" % source
        return "behind a thick lens, the paraxial equivalent of %s" % source
    if kind == "thin_lens":
        f_number = lens.f_number
        return "behind a thin main lens (f = %g mm%s)" % (
            meta.focal_length_mm, ", f/%g" % f_number if f_number is not None else "")
    if kind == "pinhole":
        return "behind a pinhole main lens"
    return "with no main lens"


def sheet_title(name: str, meta: Metadata) -> str:
    """The contact sheet's title: the file, the array and its microlenses, the main lens, the size,
    e.g. 'r.raw.png: hexagonal array of thin-lens microlenses behind a traced prescription
    (lens.dat), 640 x 480 px'."""
    lens = meta.array.lens
    focal_lengths = meta.array.focal_lengths_mm
    if lens == "pinhole":
        micro = "pinhole microlenses"
    elif len(focal_lengths) > 1:
        micro = "thin-lens microlenses of %d focal lengths" % len(focal_lengths)
    else:
        micro = "thin-lens microlenses"
    return "%s: %s array of %s %s, %d x %d px" % (name, meta.grid, micro, _main_lens_phrase(meta),
                                                  meta.width, meta.height)


def crop_marks(meta: Metadata, x0: int, y0: int, crop_w: int, crop_h: int) -> tuple[np.ndarray, np.ndarray, str]:
    """The microimage centres to mark in the raw crop [x0, x0 + crop_w) x [y0, y0 + crop_h) and
    what they are: (u, v, caption words). The centres the decoder sampled around: the metadata's
    lattice where it is exact, the measured centres of the render's microimages file behind a
    traced prescription (lenses that get no light are not marked)."""
    k, l, u, v = meta.all_centres()
    measured = measured_centres(meta)
    if measured is None:
        what = "microimage centres (metadata lattice)"
    else:
        u, v, dark = microimage_centre(meta, k, l)
        u, v = u[~dark], v[~dark]
        what = "measured centres (%s)" % os.path.basename(measured.path)
    keep = (u >= x0 - 0.5) & (u <= x0 + crop_w - 0.5) & (v >= y0 - 0.5) & (v <= y0 + crop_h - 0.5)
    return u[keep], v[keep], what


def _fitting(draw, texts, font, width):
    """The first of `texts` that is at most `width` pixels wide in `font` (else the last)."""
    for text in texts:
        if draw.textlength(text, font=font) <= width:
            return text
    return texts[-1]


def _font(size):
    """DejaVu Sans at `size` px when installed, else Pillow's default bitmap font."""
    from PIL import ImageFont
    for path in ("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                 "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf"):
        if os.path.exists(path):
            try:
                return ImageFont.truetype(path, size)
            except OSError:
                pass
    return ImageFont.load_default()


def _distance_label(distance):
    """'  (~1.23 units)' for a refocus caption; empty when the distance is unknown."""
    if distance is None:
        return ""
    if math.isinf(distance):
        return "  (~ infinity)"
    return "  (~%.3g units)" % distance


def contact_sheet(raw: np.ndarray, lf: LightField, slopes: Sequence[float] | np.ndarray,
                  refocused: Sequence[np.ndarray], near: int, far: int, epi_row: int, title: str = "") -> Image.Image:
    """One picture that shows the plenoptic effect: raw crop with the microimage centres the
    decoder sampled around (crop_marks), centre view, views from opposite sides of the aperture, an EPI, near and far refocus.

    raw: the linear raw image; lf: its LightField; refocused[i]: lf refocused at slopes[i];
    near, far: indices into slopes; epi_row: lens row of the EPI. Returns a PIL image."""
    from PIL import Image, ImageDraw
    meta = lf.meta
    panel_w, panel_h, pad = 300, 225, 12
    title_font, label_font, small_font = _font(18), _font(14), _font(11)
    panels = []  # (PIL image, label, caption)

    # 1. Raw crop around the image centre, about five microimages across, lattice centres marked.
    pitch = np.hypot(*meta.a)
    H, W = raw.shape[:2]
    crop_w = int(min(W, max(16, round(5.5 * pitch))))
    crop_h = int(min(H, max(12, round(crop_w * panel_h / panel_w))))
    x0, y0 = (W - crop_w) // 2, (H - crop_h) // 2
    crop = raw[y0:y0 + crop_h, x0:x0 + crop_w]
    im = scaled_pil_image(crop, panel_w, panel_h)
    scale = im.size[0] / crop_w
    draw = ImageDraw.Draw(im)
    centres_u, centres_v, marked = crop_marks(meta, x0, y0, crop_w, crop_h)
    for u, v in zip(centres_u, centres_v):
        px, py = (u - x0 + 0.5) * scale, (v - y0 + 0.5) * scale
        draw.line([(px - 3, py), (px + 3, py)], fill=(255, 60, 60))
        draw.line([(px, py - 3), (px, py + 3)], fill=(255, 60, 60))
    caption = _fitting(draw, ["%d x %d px; + = %s" % (crop_w, crop_h, marked), "+ = %s" % marked,
                              "+ = %s" % marked.split(" (")[0]], small_font, panel_w + pad - 4)
    panels.append((im, "Raw lenslet image (crop)", caption))

    aspect = lf.display_aspect()
    cv, cu = lf.centre_index()
    panels.append((scaled_pil_image(lf.view(cv, cu), panel_w, panel_h, aspect), "Centre view",
                   "%d x %d lenses, one pixel per lens" % (lf.shape[1], lf.shape[0])))
    usable = [iu for iu in range(len(lf.du)) if lf.mask[cv, iu]]
    left, right = usable[0], usable[-1]
    panels.append((scaled_pil_image(lf.view(cv, left), panel_w, panel_h, aspect), "View from the aperture's left",
                   "u offset %+.3g px" % lf.du[left]))
    panels.append((scaled_pil_image(lf.view(cv, right), panel_w, panel_h, aspect), "View from the aperture's right",
                   "u offset %+.3g px (compare with the left view)" % lf.du[right]))

    # EPI, stretched to fill its (double-width) panel: a tilted streak is a point off the focus plane.
    epi, epi_u = lf.epi(epi_row, cv)
    epi_im = Image.fromarray(to_8bit(epi)).resize((2 * panel_w + pad, panel_h), Image.NEAREST)
    panels.append((epi_im, "Epipolar-plane image (lens row %d of the views)" % epi_row,
                   "across: lens s; down: view u %+.3g..%+.3g px; vertical = in focus, tilt = nearer or farther"
                   % (lf.du[epi_u[0]], lf.du[epi_u[-1]])))
    for name, index in (("Refocused near", near), ("Refocused far", far)):
        distance = lf.slope_to_distance(slopes[index])
        panels.append((scaled_pil_image(refocused[index], panel_w, panel_h, aspect), name,
                       "slope %+.3f lens/view%s" % (slopes[index], _distance_label(distance))))

    # Layout: first row 4 panels, second row EPI (double width) + 2 refocus.
    label_h, caption_h, head_h = 20, 16, 34 if title else 8
    cell_w, cell_h = panel_w + pad, panel_h + label_h + caption_h + pad
    sheet_w = 4 * cell_w + pad
    sheet_h = head_h + 2 * cell_h + pad
    sheet = Image.new("RGB", (sheet_w, sheet_h), (24, 24, 28))
    draw = ImageDraw.Draw(sheet)
    if title:
        # A long title (a lens file's name) in a smaller font rather than past the sheet's edge.
        for size in (18, 17, 16, 15, 14, 13, 12):
            title_font = _font(size)
            if draw.textlength(title, font=title_font) <= sheet_w - 2 * pad:
                break
        draw.text((pad, 8), title, fill=(240, 240, 240), font=title_font)
    slots = [(0, 0, 1), (1, 0, 1), (2, 0, 1), (3, 0, 1), (0, 1, 2), (2, 1, 1), (3, 1, 1)]  # (column, row, span)
    for (im, label, caption), (column, row, span) in zip(panels, slots):
        x = pad + column * cell_w
        y = head_h + row * cell_h
        draw.text((x, y), label, fill=(255, 255, 255), font=label_font)
        box_w = span * cell_w - pad
        paste_x = x + (box_w - im.size[0]) // 2
        paste_y = y + label_h + (panel_h - im.size[1]) // 2
        draw.rectangle([x - 1, y + label_h - 1, x + box_w, y + label_h + panel_h], outline=(70, 70, 80))
        sheet.paste(im, (paste_x, paste_y))
        draw.text((x, y + label_h + panel_h + 3), caption, fill=(190, 190, 200), font=small_font)
    return sheet
