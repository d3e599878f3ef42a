# SPDX-License-Identifier: AGPL-3.0-or-later
"""The render's measured microimage centres, <stem>.microimages.csv (docs/metadata.md,
"Microimage centres"), for decoding renders behind a traced prescription, whose microimages
leave the metadata's paraxial lattice (pupil aberration, vignetting; docs/real-lenses.md).

The file has one line per lens whose lattice centre lies in the picture: k, l (row form), u, v
(the centroid of a white scene's light, pixels; empty for a lens that gets no light), then
lit_fraction and the residuals. A render with spectral sampling adds the centres per channel,
u_r, v_r, u_g, v_g, u_b, v_b (empty where that channel's microimage gets no light); both forms are
read (MeasuredCentres.channel_centre). Lenses are looked up by skew index (k_s, l) as the
metadata's lattice numbers them: k_s = k - floor(l / 2) on a hexagonal grid, k_s = k on a
rectangular one.
"""

import math
import os

import numpy as np

from .errors import DecodeError

COLUMNS = ("k", "l", "u", "v")
# The centres per channel of a spectral render, after the other columns.
CHANNEL_COLUMNS = ("u_r", "v_r", "u_g", "v_g", "u_b", "v_b")
# The lookup's status of a lens.
UNLISTED, LIT, DARK = 0, 1, 2


def _lattice_fit(meta):
    """(origin, a, b) of the metadata's microimages.lattice_fit, or None when it has none (fewer
    than three lit lenses) or it is malformed."""
    return meta.microimages.lattice_fit


class MeasuredCentres:
    """Per-lens measured centres: centre(k, l) -> (u, v, dark), skew indices, vectorised.

    A lit lens gives its measured centre; a lens the file lists without a centre (no light) is
    dark, and gives the lattice fit's position; a lens the file does not list (its lattice centre
    lies outside the picture) gives the lattice fit's position, or the metadata lattice's when
    the JSON has no fit."""

    def __init__(self, meta, path):
        self.path = path
        self.meta = meta
        rows, channel_rows = self._read(path)
        hexagonal = meta.grid == "hexagonal"
        keys = [(k - (l // 2 if hexagonal else 0), l) for k, l, _, _ in rows]
        if rows:
            k_values = [key[0] for key in keys]
            l_values = [key[1] for key in keys]
            self.k_min, self.l_min = min(k_values), min(l_values)
            shape = (max(l_values) - self.l_min + 1, max(k_values) - self.k_min + 1)
        else:
            self.k_min = self.l_min = 0
            shape = (1, 1)
        if shape[0] * shape[1] > 50_000_000:
            raise DecodeError("%s: its lenses span %d x %d indices, far more than any picture holds"
                              % (path, shape[1], shape[0]))
        self.u = np.full(shape, np.nan)
        self.v = np.full(shape, np.nan)
        self.status = np.zeros(shape, np.int8)
        for (ks, l), (_, _, u, v) in zip(keys, rows):
            i, j = l - self.l_min, ks - self.k_min
            self.status[i, j] = DARK if u is None else LIT
            if u is not None:
                self.u[i, j], self.v[i, j] = u, v
        # Per channel (spectral renders): u, v arrays of the same shape, NaN where not lit.
        self.has_channels = channel_rows is not None
        self.channel_u = [np.full(shape, np.nan) for _ in range(3)]
        self.channel_v = [np.full(shape, np.nan) for _ in range(3)]
        for (ks, l), centres in zip(keys, channel_rows or []):
            for c, (u, v) in enumerate(centres):
                if u is not None:
                    self.channel_u[c][l - self.l_min, ks - self.k_min] = u
                    self.channel_v[c][l - self.l_min, ks - self.k_min] = v
        self.lenses = len(rows)
        self.dark_lenses = int((self.status == DARK).sum())
        self.fit = _lattice_fit(meta)

    @staticmethod
    def _centre(path, number, u_text, v_text):
        """(u, v) of two cells, (None, None) when both are empty; DecodeError naming the line."""
        if u_text == "" and v_text == "":
            return None, None
        try:
            u, v = float(u_text), float(v_text)
        except ValueError:
            u = v = math.nan
        if not (math.isfinite(u) and math.isfinite(v)):
            raise DecodeError("%s, line %d: the centre u, v must be two finite numbers (or both empty for a lens "
                              "that gets no light), found %r, %r" % (path, number, u_text, v_text))
        return u, v

    @staticmethod
    def _read(path):
        """([(k, l, u or None, v or None)], per channel [((u_r, v_r), (u_g, v_g), (u_b, v_b))] or None
        without those columns) from the file, checked; DecodeError naming the line."""
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError as e:
            raise DecodeError("cannot read the microimage centres %s: %s" % (path, e.strerror or e))
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            raise DecodeError("%s: not UTF-8 text, not a microimage centres file" % path)
        lines = text.splitlines()
        if not lines:
            raise DecodeError("%s is empty: it must start with the header k,l,u,v,..." % path)
        header = [c.strip() for c in lines[0].split(",")]
        if tuple(header[:4]) != COLUMNS:
            raise DecodeError("%s, line 1: the header must start with k,l,u,v, found %r" % (path, lines[0][:80]))
        channel_at = None
        if all(c in header for c in CHANNEL_COLUMNS):
            channel_at = [header.index(c) for c in CHANNEL_COLUMNS]
        rows, channel_rows = [], [] if channel_at else None
        seen = set()
        for number, line in enumerate(lines[1:], start=2):
            if not line.strip():
                continue
            cells = [c.strip() for c in line.split(",")]
            if len(cells) != len(header):
                raise DecodeError("%s, line %d: %d values where the header names %d" % (path, number, len(cells), len(header)))
            try:
                k, l = int(cells[0]), int(cells[1])
            except ValueError:
                raise DecodeError("%s, line %d: the lens index k, l must be whole numbers, found %r, %r"
                                  % (path, number, cells[0], cells[1]))
            if (k, l) in seen:
                raise DecodeError("%s, line %d: lens (%d, %d) is listed twice" % (path, number, k, l))
            seen.add((k, l))
            u, v = MeasuredCentres._centre(path, number, cells[2], cells[3])
            rows.append((k, l, u, v))
            if channel_at:
                channel_rows.append(tuple(MeasuredCentres._centre(path, number, cells[channel_at[2 * c]],
                                                                  cells[channel_at[2 * c + 1]]) for c in range(3)))
        return rows, channel_rows

    def channel_centre(self, channel, k, l):
        """(u, v, dark) of channel 0 (R), 1 (G) or 2 (B) for skew indices k, l, as centre() gives
        them (the fallbacks the same); a file without centres per channel gives centre()'s."""
        u, v, dark = self.centre(k, l)
        if not self.has_channels:
            return u, v, dark
        _, _, listed, ii, jj = self._cells(k, l)
        cu = np.where(listed, self.channel_u[channel][ii, jj], np.nan)
        cv = np.where(listed, self.channel_v[channel][ii, jj], np.nan)
        lit = np.isfinite(cu)
        return np.where(lit, cu, u), np.where(lit, cv, v), dark & ~lit

    def _fallback(self, k, l):
        if self.fit is None:
            return self.meta.centre(k, l)
        origin, a, b = self.fit
        return origin[0] + k * a[0] + l * b[0], origin[1] + k * a[1] + l * b[1]

    def _cells(self, k, l):
        """k, l as float arrays; which of them the file lists; their row and column in the
        tables (0 where not listed)."""
        k = np.asarray(k, dtype=float)
        l = np.asarray(l, dtype=float)
        i = np.rint(l).astype(np.int64) - self.l_min
        j = np.rint(k).astype(np.int64) - self.k_min
        listed = (i >= 0) & (i < self.status.shape[0]) & (j >= 0) & (j < self.status.shape[1])
        return k, l, listed, np.where(listed, i, 0), np.where(listed, j, 0)

    def centre(self, k, l):
        """(u, v, dark) for skew indices k, l (arrays of whole numbers as floats)."""
        k, l, listed, ii, jj = self._cells(k, l)
        status = np.where(listed, self.status[ii, jj], UNLISTED)
        fallback_u, fallback_v = self._fallback(k, l)
        lit = status == LIT
        u = np.where(lit, self.u[ii, jj], fallback_u)
        v = np.where(lit, self.v[ii, jj], fallback_v)
        return u, v, status == DARK


# Tolerance, in pixels, of the check that a centres file lists the lenses whose lattice centre lies
# in the picture (the renderer's rule): lattice centres closer than this to the picture's edge
# are not checked either way.
_EDGE_TOLERANCE_PX = 0.01


def metadata_stem(meta_path):
    """'<dir>/shot001' for '<dir>/shot001.plenoptic.json' (any other name: without its extension)."""
    name = os.path.basename(meta_path)
    stem = name[:-len(".plenoptic.json")] if name.endswith(".plenoptic.json") else os.path.splitext(name)[0]
    return os.path.join(os.path.dirname(os.path.abspath(meta_path)), stem)


def microimages_candidates(meta):
    """The files measured_centres looks for, in order, with what each is: the metadata's
    microimages.file beside the metadata, then <metadata stem>.microimages.csv (the name the
    renderer would give it, for a render whose files were renamed). Empty when the metadata says
    the render wrote none."""
    name = meta.microimages.file
    if name is None:
        return []
    candidates = [(os.path.join(os.path.dirname(os.path.abspath(meta.path)), name),
                   "the metadata's microimages.file")]
    renamed = metadata_stem(meta.path) + ".microimages.csv"
    if os.path.normpath(renamed) != os.path.normpath(candidates[0][0]):
        candidates.append((renamed, "<metadata stem>.microimages.csv"))
    return candidates


def check_centres_belong(meta, centres):
    """DecodeError when the centres file cannot be this render's: its lens count differs from the
    metadata's microimages.lenses, or it does not list exactly the lenses whose microimage_lattice
    centre lies in the picture, as the renderer writes it (docs/metadata.md, "Microimage centres")."""
    path = centres.path
    counted = meta.microimages.lenses
    if counted is not None and centres.lenses != counted:
        raise DecodeError("%s lists %d lenses, but this render's metadata counts %d (microimages.lenses): the centres "
                          "belong to another render, or the file was cut" % (path, centres.lenses, counted))
    W, H, tol = meta.width, meta.height, _EDGE_TOLERANCE_PX
    listed = centres.status != UNLISTED
    ll, kk = np.nonzero(listed)
    k, l = kk + centres.k_min, ll + centres.l_min
    u, v = meta.centre(k, l)
    outside = (u < -0.5 - tol) | (u > W - 0.5 + tol) | (v < -0.5 - tol) | (v > H - 0.5 + tol)
    if outside.any():
        i = int(np.argmax(outside))
        raise DecodeError("%s lists lens (k_s %d, l %d), whose microimage_lattice centre (%.2f, %.2f) lies outside this "
                          "%d x %d picture: the centres belong to another render" % (path, k[i], l[i], u[i], v[i], W, H))
    k_all, l_all, _, _ = meta.all_centres(margin=-0.5 + tol)
    i = l_all - centres.l_min
    j = k_all - centres.k_min
    inside = (i >= 0) & (i < centres.status.shape[0]) & (j >= 0) & (j < centres.status.shape[1])
    missing = ~inside.copy()
    missing[inside] = centres.status[i[inside], j[inside]] == UNLISTED
    if missing.any():
        n = int(np.argmax(missing))
        raise DecodeError("%s does not list lens (k_s %d, l %d), whose microimage_lattice centre lies in this %d x %d "
                          "picture (%d such lenses missing): the centres belong to another render, or the file was cut"
                          % (path, k_all[n], l_all[n], W, H, int(missing.sum())))


def measured_centres(meta):
    """The MeasuredCentres of a render whose microimages leave the metadata lattice (a traced
    prescription), None when the lattice is exact. The file is meta.microimages_file
    (plenoptic-decode --microimages) when set, else the first of microimages_candidates that
    exists; it must belong to this render (check_centres_belong). DecodeError, saying why, what
    was tried and how to give the file, when there is none."""
    if meta.lattice_is_exact:
        return None
    cached = getattr(meta, "_measured_centres", None)
    if cached is not None:
        return cached
    why = ("this render's main lens is a traced prescription, whose microimage centres leave the metadata's "
           "paraxial lattice (pupil aberration and vignetting move them by up to a pixel and more at the edge of "
           "the field), so the decoder samples each microimage around its measured centre from the render's "
           "<image>.microimages.csv")
    path = getattr(meta, "microimages_file", None)
    if path is not None:
        if not os.path.isfile(path):
            raise DecodeError("--microimages %s: no such file" % path)
    else:
        candidates = microimages_candidates(meta)
        if not candidates:
            raise DecodeError("%s; this render wrote none (its metadata's 'microimages' is null: the camera said "
                              "microimage_centres off). Render it again with microimage_centres (the default behind "
                              "a prescription), or give measured centres with --microimages CSV" % why)
        found = [p for p, _ in candidates if os.path.isfile(p)]
        if not found:
            raise DecodeError("%s; tried %s, and %s: give the file with --microimages CSV (or render again "
                              "with microimage_centres)"
                              % (why, " and ".join("%s (%s)" % c for c in candidates),
                                 "neither exists" if len(candidates) > 1 else "it does not exist"))
        path = found[0]
    centres = MeasuredCentres(meta, path)
    check_centres_belong(meta, centres)
    meta._measured_centres = centres
    return centres


def microimage_centre(meta, k, l):
    """(u, v, dark) of the microimages of skew lens indices (k, l): the metadata lattice where it
    is exact (dark all False), else the measured centres (measured_centres)."""
    centres = measured_centres(meta)
    if centres is None:
        u, v = meta.centre(k, l)
        return u, v, np.zeros(np.shape(u), bool)
    return centres.centre(k, l)
