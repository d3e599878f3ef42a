# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-lens: a main lens's prescription from an optical-design file, its first-order data and
a drawing of it (docs/plenoptic-lens.md).

    plenoptic-lens import LENS.zmx -o lens.dat [--catalogue GLASS.agf ...]
    plenoptic-lens info LENS [--json] [--catalogue GLASS.agf ...]
    plenoptic-lens draw LENS -o lens.png [--field DEG ...] [--size WxH] [--catalogue GLASS.agf ...]

LENS is a lens file (pbrt's rows, as main_lens { lens_file } reads them) or a Zemax sequential
.zmx file, imported in memory. The optics (paraxial data, colour, surface profiles, traced rays)
are the optics core's, through the program plenoptic-lens-data built beside the renderer; this
module reads the .zmx and the glass catalogue, writes the lens file, prints and draws.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from typing import Any, Dict, List, Optional, Sequence, Tuple

from .locate import find_lens_data

# The Fraunhofer lines (µm) at which the catalogue's index is evaluated: F, d, C, the values of
# source/plenoptic/lens/glass.h (kLineFNm, kLineDNm, kLineCNm).
LINE_F_UM = 0.4861327
LINE_D_UM = 0.5875618
LINE_C_UM = 0.6562725

# The .zmx lens units and their length in mm.
UNITS = {"MM": 1.0, "CM": 10.0, "IN": 25.4, "METER": 1000.0, "METERS": 1000.0, "M": 1000.0}

# Radius written for a flat refracting surface: the lens file has no flat notation (radius 0 is
# the stop), and a radius beyond 1e12 mm is read as flat (docs/real-lenses.md).
FLAT_RADIUS = "1e20"

# Surface keywords read, and those ignored because they only describe how Zemax draws, labels or
# analyses a surface (nothing a ray meets).
SURFACE_KEYWORDS = {"TYPE", "CURV", "DISZ", "DIAM", "CONI", "PARM", "STOP", "GLAS", "CLAP"}
IGNORED_SURFACE_KEYWORDS = {
    "COMM": "a comment",
    "HIDE": "drawing: hidden in layouts",
    "SLAB": "a label",
    "MIRR": "drawing: a mirror's substrate",
    "MEMA": "drawing: the mechanical semi-diameter",
    "FLAP": "drawing: the flat rim",
    "POPS": "physical-optics propagation settings",
    "COAT": "a coating (the camera has no coatings)",
}
# The even asphere's PARM 2 .. 9: the coefficients of r^4 .. r^18.
MAX_EVENASPH_PARM = 9


class LensToolError(Exception):
    """A refusal: one line naming the file, the line, the keyword and what is allowed."""


def decode_text(data: bytes) -> Tuple[str, str]:
    """The text of a file that may be UTF-16 (with a byte-order mark, or without one but with the
    zero bytes of ASCII text in UTF-16), UTF-8 (with or without a mark) or Windows-1252; and the
    encoding's name."""
    if data.startswith(b"\xff\xfe"):
        return data[2:].decode("utf-16-le"), "UTF-16 LE"
    if data.startswith(b"\xfe\xff"):
        return data[2:].decode("utf-16-be"), "UTF-16 BE"
    if data.startswith(b"\xef\xbb\xbf"):
        return data[3:].decode("utf-8"), "UTF-8"
    if len(data) >= 4 and data[1] == 0 and data[3] == 0 and data[0] != 0:
        return data.decode("utf-16-le"), "UTF-16 LE"
    if len(data) >= 4 and data[0] == 0 and data[2] == 0 and data[1] != 0:
        return data.decode("utf-16-be"), "UTF-16 BE"
    try:
        return data.decode("utf-8"), "UTF-8"
    except UnicodeDecodeError:
        return data.decode("cp1252", errors="replace"), "Windows-1252"


def read_text(path: str) -> Tuple[str, str]:
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise LensToolError("%s: cannot read it (%s)" % (path, e.strerror or e))
    try:
        return decode_text(data)
    except UnicodeDecodeError as e:
        raise LensToolError("%s: not text in UTF-16 or UTF-8 (%s)" % (path, e))


def number(token: str, where: str, what: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise LensToolError("%s: %s '%s' is not a number" % (where, what, token))
    if not math.isfinite(value):
        raise LensToolError("%s: %s '%s' is not a finite number" % (where, what, token))
    return value


def fmt(value: float) -> str:
    """A number for the lens file: 10 significant digits, no trailing noise."""
    if value == 0:
        return "0"
    return "%.10g" % value


# ----------------------------------------------------------------------------------------------
# Glass catalogues (Zemax AGF)
#
# The AGF format as OpticStudio's manual ("The AGF & BGF File Formats") publishes it: a record per
# glass, `NM <name> <dispersion formula #> <MIL#> <N(d)> <V(d)> <exclude sub> <status> <melt freq>`,
# followed by `CD <dispersion coefficients 1 - 10>` (and other records, TD, ED, LD, IT..., not
# needed here). Formula numbers (the same manual, GETGLASSDATA): 1 Schott, 2 Sellmeier 1,
# 3 Herzberger, 4 Sellmeier 2, 5 Conrady, 6 Sellmeier 3, 7 and 8 Handbook of Optics 1 and 2,
# 9 Sellmeier 4, 10 Extended, 11 Sellmeier 5, 12 Extended 2. Read here: 1 and 2, which the major
# vendors' catalogues use; the others are refused by name. Lambda in µm:
#   Schott:       n^2 = a0 + a1 l^2 + a2 l^-2 + a3 l^-4 + a4 l^-6 + a5 l^-8
#   Sellmeier 1:  n^2 - 1 = K1 l^2 / (l^2 - L1) + K2 l^2 / (l^2 - L2) + K3 l^2 / (l^2 - L3),
#                 CD K1 L1 K2 L2 K3 L3
# ----------------------------------------------------------------------------------------------

FORMULA_NAMES = {1: "Schott", 2: "Sellmeier 1", 3: "Herzberger", 4: "Sellmeier 2", 5: "Conrady",
                 6: "Sellmeier 3", 7: "Handbook of Optics 1", 8: "Handbook of Optics 2", 9: "Sellmeier 4",
                 10: "Extended", 11: "Sellmeier 5", 12: "Extended 2", 13: "Extended 3"}


class CatalogueGlass:
    def __init__(self, name, formula, nd, vd, path, line):
        self.name, self.formula, self.nd, self.vd = name, formula, nd, vd
        self.path, self.line = path, line
        self.coefficients: List[float] = []

    def index(self, wavelength_um: float) -> float:
        l2 = wavelength_um * wavelength_um
        c = self.coefficients + [0.0] * 10
        if self.formula == 1:
            n2 = c[0] + c[1] * l2 + c[2] / l2 + c[3] / l2 ** 2 + c[4] / l2 ** 3 + c[5] / l2 ** 4
        elif self.formula == 2:
            n2 = 1 + sum(c[2 * i] * l2 / (l2 - c[2 * i + 1]) for i in range(3))
        else:
            raise LensToolError("%s:%d: glass %s uses dispersion formula %d (%s); the importer reads formulas "
                                "1 (Schott) and 2 (Sellmeier 1)"
                                % (self.path, self.line, self.name, self.formula,
                                   FORMULA_NAMES.get(self.formula, "unknown")))
        if not n2 > 1:
            raise LensToolError("%s:%d: glass %s's formula gives n^2 = %g at %g µm"
                                % (self.path, self.line, self.name, n2, wavelength_um))
        return math.sqrt(n2)

    def nd_vd(self) -> Tuple[float, float]:
        """n_d and V_d = (n_d - 1) / (n_F - n_C) from the catalogue's formula."""
        nd, nf, nc = self.index(LINE_D_UM), self.index(LINE_F_UM), self.index(LINE_C_UM)
        if not nf > nc:
            raise LensToolError("%s:%d: glass %s does not disperse normally (n_F %.6f <= n_C %.6f)"
                                % (self.path, self.line, self.name, nf, nc))
        return nd, (nd - 1) / (nf - nc)


def read_catalogue(path: str) -> Dict[str, CatalogueGlass]:
    """The glasses of an AGF file, by upper-case name."""
    text, _ = read_text(path)
    glasses: Dict[str, CatalogueGlass] = {}
    current: Optional[CatalogueGlass] = None
    for number_, line in enumerate(text.splitlines(), 1):
        tokens = line.split()
        if not tokens:
            continue
        where = "%s:%d" % (path, number_)
        if tokens[0] == "NM":
            if len(tokens) < 6:
                raise LensToolError("%s: NM needs a glass name, a formula number, a MIL number, N(d) and V(d)" % where)
            formula = number(tokens[2], where, "NM's dispersion formula number")
            current = CatalogueGlass(tokens[1], int(formula), number(tokens[4], where, "NM's N(d)"),
                                     number(tokens[5], where, "NM's V(d)"), path, number_)
            glasses[tokens[1].upper()] = current
        elif tokens[0] == "CD" and current is not None:
            current.coefficients = [number(t, where, "a CD coefficient") for t in tokens[1:]]
    if not glasses:
        raise LensToolError("%s: no glass (NM line) in it: a glass catalogue in Zemax's AGF format is expected" % path)
    return glasses


# ----------------------------------------------------------------------------------------------
# Zemax sequential files (.zmx)
#
# The .zmx format has no published specification (Zemax's manual stopped describing it about 2005,
# as its support staff say on the Zemax community forum, "ZMX file specification"); what is read
# here is the plain-text layout such files show: top-level keywords (MODE, UNIT, NAME, GCAT ...)
# and `SURF n` blocks of indented keywords: TYPE, CURV (curvature, 1/length), DISZ (thickness to
# the next surface, INFINITY for an object at infinity), DIAM (semi-diameter), CONI (conic
# constant), PARM n (the surface type's parameters: EVENASPH's PARM 1 .. 8 are the coefficients
# of r^2 .. r^16), STOP, GLAS. The glass line of a model glass (OpticStudio's "Model" glass solve,
# described by n_d, V_d and the partial-dispersion deviation dPgF) is
#   GLAS ___BLANK 1 0 <n_d> <V_d> <dPgF> ...
# (solve type 1); a catalogue glass is `GLAS <name> 0 ...`, looked up in the catalogue the user
# names. The object surface (SURF 0) and the image surface (the last) are not rows of the lens.
# ----------------------------------------------------------------------------------------------

class ZmxSurface:
    def __init__(self, number_: int, line: int):
        self.number, self.line = number_, line
        self.type, self.type_line = "STANDARD", line
        self.curv = 0.0
        self.disz: Optional[float] = None
        self.disz_line = line
        self.diam: Optional[float] = None
        self.clap: Optional[float] = None
        self.conic = 0.0
        self.parm: Dict[int, Tuple[float, int]] = {}
        self.stop = False
        self.glass: Optional[List[str]] = None
        self.glass_line = line


class Medium:
    def __init__(self, nd=1.0, vd=0.0, note=""):
        self.nd, self.vd, self.note = nd, vd, note


class Imported:
    """A .zmx converted: the lens file's text, and for each of its lines that holds a row the .zmx
    surface and line it came from."""

    def __init__(self, text: str, origins: Dict[int, Tuple[int, int]]):
        self.text, self.origins = text, origins


def parse_zmx(text: str, path: str) -> Tuple[List[ZmxSurface], Dict[str, Any]]:
    surfaces: List[ZmxSurface] = []
    info: Dict[str, Any] = {"unit": "MM", "unit_line": 0, "name": "", "gcat": []}
    current: Optional[ZmxSurface] = None
    for n, raw in enumerate(text.splitlines(), 1):
        tokens = raw.split()
        if not tokens:
            continue
        key = tokens[0].upper()
        where = "%s:%d" % (path, n)
        indented = raw[:1] in (" ", "\t")
        if not indented:
            current = None
            if key == "SURF":
                if len(tokens) < 2:
                    raise LensToolError("%s: SURF needs the surface number" % where)
                current = ZmxSurface(int(number(tokens[1], where, "SURF's number")), n)
                surfaces.append(current)
            elif key == "MODE" and len(tokens) > 1 and tokens[1].upper() != "SEQ":
                raise LensToolError("%s: MODE %s: only sequential files (MODE SEQ) can be imported" % (where, tokens[1]))
            elif key == "UNIT":
                if len(tokens) < 2 or tokens[1].upper() not in UNITS:
                    raise LensToolError("%s: UNIT %s: the lens units must be MM, CM, IN or METER"
                                        % (where, tokens[1] if len(tokens) > 1 else "(none)"))
                info["unit"], info["unit_line"] = tokens[1].upper(), n
            elif key == "NAME":
                info["name"] = raw.strip()[4:].strip()
            elif key == "GCAT":
                info["gcat"] = tokens[1:]
            elif key == "MNUM" and len(tokens) > 1 and number(tokens[1], where, "MNUM") > 1:
                raise LensToolError("%s: MNUM %s: a multi-configuration (zoom) file; the importer reads a single "
                                    "configuration" % (where, tokens[1]))
            continue
        if current is None:
            continue  # continuation of a top-level record
        s = current
        if key in IGNORED_SURFACE_KEYWORDS:
            continue
        if key not in SURFACE_KEYWORDS:
            raise LensToolError("%s: %s on surface %d: not a keyword the importer reads (it reads %s; it ignores %s); "
                                "tilts, decentres and other surface properties cannot be represented in a lens file"
                                % (where, key, s.number, ", ".join(sorted(SURFACE_KEYWORDS)),
                                   ", ".join(sorted(IGNORED_SURFACE_KEYWORDS))))
        if key == "STOP":
            s.stop = True
        elif key == "TYPE":
            s.type, s.type_line = (tokens[1].upper() if len(tokens) > 1 else ""), n
        elif len(tokens) < 2:
            raise LensToolError("%s: %s on surface %d needs a value" % (where, key, s.number))
        elif key == "CURV":
            s.curv = number(tokens[1], where, "CURV")
        elif key == "DISZ":
            s.disz = math.inf if tokens[1].upper() in ("INFINITY", "INF") else number(tokens[1], where, "DISZ")
            s.disz_line = n
        elif key == "DIAM":
            s.diam = number(tokens[1], where, "DIAM (the semi-diameter)")
        elif key == "CLAP":
            lo = number(tokens[1], where, "CLAP's minimum radius")
            hi = number(tokens[2], where, "CLAP's maximum radius") if len(tokens) > 2 else 0.0
            if lo != 0 or not hi > 0:
                raise LensToolError("%s: CLAP %s %s on surface %d: only a circular aperture from the axis (minimum "
                                    "radius 0, maximum > 0) can be represented" % (where, tokens[1],
                                                                                tokens[2] if len(tokens) > 2 else "",
                                                                                s.number))
            s.clap = hi
        elif key == "CONI":
            s.conic = number(tokens[1], where, "CONI")
        elif key == "PARM":
            if len(tokens) < 3:
                raise LensToolError("%s: PARM on surface %d needs an index and a value" % (where, s.number))
            s.parm[int(number(tokens[1], where, "PARM's index"))] = (number(tokens[2], where, "PARM's value"), n)
        elif key == "GLAS":
            s.glass, s.glass_line = tokens[1:], n
    return surfaces, info


def surface_type_refusal(s: ZmxSurface, path: str) -> None:
    if s.type in ("STANDARD", "EVENASPH"):
        return
    what = "a surface type"
    if s.type == "COORDBRK":
        what = "a coordinate break (a tilt or decentre)"
    elif s.type.startswith("GRIN") or s.type.startswith("GRADIENT") or s.type.startswith("GRADIUM"):
        what = "a gradient-index surface"
    elif s.type == "PARAXIAL" or s.type == "PARAX_XY":
        what = "a paraxial (ideal) surface"
    raise LensToolError("%s:%d: TYPE %s on surface %d is %s that a lens file cannot represent; the importer reads "
                        "TYPE STANDARD and EVENASPH" % (path, s.type_line, s.type or "(none)", s.number, what))


def surface_medium(s: ZmxSurface, path: str, catalogues: Sequence[Tuple[str, Dict[str, CatalogueGlass]]],
                   gcat: Sequence[str]) -> Medium:
    """The medium after surface s (its GLAS line; none: air)."""
    if s.glass is None or not s.glass:
        return Medium()
    where = "%s:%d" % (path, s.glass_line)
    name = s.glass[0]
    if name.upper() == "MIRROR":
        raise LensToolError("%s: GLAS MIRROR on surface %d: mirrors cannot be represented (a lens file holds "
                            "refracting surfaces only)" % (where, s.number))
    if name.upper() == "AIR":
        return Medium()
    solve = s.glass[1] if len(s.glass) > 1 else "0"
    if solve == "1":
        if len(s.glass) < 5:
            raise LensToolError("%s: the model glass of surface %d needs n_d and V_d (GLAS ___BLANK 1 0 n_d V_d dPgF)"
                                % (where, s.number))
        nd = number(s.glass[3], where, "the model glass's n_d")
        vd = number(s.glass[4], where, "the model glass's V_d")
        dpgf = number(s.glass[5], where, "the model glass's dPgF") if len(s.glass) > 5 else 0.0
        if nd < 1:
            raise LensToolError("%s: the model glass of surface %d has n_d %s below 1" % (where, s.number, s.glass[3]))
        note = "surface %d: model glass n_d %s, V_d %s" % (s.number, fmt(nd), fmt(vd))
        if dpgf != 0:
            note += " (its dPgF %s is dropped: the lens file's two-term dispersion has no partial-dispersion term)" % fmt(dpgf)
        return Medium(nd, vd, note)
    if name == "___BLANK" or solve != "0":
        raise LensToolError("%s: GLAS %s on surface %d: a glass solve of type %s; the importer reads a model glass "
                            "(GLAS ___BLANK 1 0 n_d V_d ...) or a catalogue glass (GLAS NAME 0 ...)"
                            % (where, " ".join(s.glass[:2]), s.number, solve))
    for cat_path, glasses in catalogues:
        glass = glasses.get(name.upper())
        if glass is not None:
            nd, vd = glass.nd_vd()
            note = ("surface %d: %s from %s (line %d, formula %d, %s): n_d %.6f and V_d %.4f computed from the formula "
                    "at the d, F and C lines (the catalogue's NM line prints %s, %s)"
                    % (s.number, glass.name, os.path.basename(cat_path), glass.line, glass.formula,
                       FORMULA_NAMES.get(glass.formula, "?"), nd, vd, fmt(glass.nd), fmt(glass.vd)))
            return Medium(nd, vd, note)
    looked = (" (looked up in %s)" % ", ".join(p for p, _ in catalogues)) if catalogues else ""
    raise LensToolError("%s: GLAS %s on surface %d: a catalogue glass not found%s; give the catalogue that holds it "
                        "with --catalogue FILE.agf (the file names %s)"
                        % (where, name, s.number, looked, " ".join(gcat) if gcat else "no catalogue"))


def zmx_to_lens_file(text: str, path: str, encoding: str = "UTF-8",
                     catalogue_paths: Sequence[str] = ()) -> Imported:
    """The lens file of a .zmx file's text (path names it in refusals and the header)."""
    surfaces, info = parse_zmx(text, path)
    if len(surfaces) < 3:
        raise LensToolError("%s: %d SURF block%s: a lens needs the object surface, at least one lens surface and the "
                            "image surface" % (path, len(surfaces), "" if len(surfaces) == 1 else "s"))
    scale = UNITS[info["unit"]]
    catalogues = [(p, read_catalogue(p)) for p in catalogue_paths]
    obj, lens, image = surfaces[0], surfaces[1:-1], surfaces[-1]
    header = ["# Imported by plenoptic-lens from %s (a Zemax sequential file, %s)." % (os.path.basename(path), encoding)]
    if info["name"]:
        header.append("# Its NAME: %s" % info["name"])
    header.append("# Units: %s%s." % (info["unit"], "" if scale == 1 else ", converted to mm (x %s)" % fmt(scale)))
    for s in surfaces:
        surface_type_refusal(s, path)
    if surface_medium(obj, path, catalogues, info["gcat"]).nd != 1:
        raise LensToolError("%s:%d: the object surface (SURF 0) is in glass; the lens must be in air" % (path, obj.glass_line))
    if obj.disz is None or math.isinf(obj.disz):
        header.append("# Object at infinity (SURF 0, not a row).")
    else:
        header.append("# The file's object lies %s mm in front of surface 1 (SURF 0, not a row: the camera's focus "
                      "sets the object distance)." % fmt(obj.disz * scale))
    header.append("# Image surface SURF %d (not a row): the last row's thickness is the file's distance to it." % image.number)

    rows: List[Dict[str, Any]] = []
    media: List[Medium] = []
    before = Medium()
    stops = [s for s in lens if s.stop]
    if len(stops) != 1:
        raise LensToolError("%s: %s: a lens file needs exactly one stop (STOP on one surface between the object and "
                            "the image)" % (path, "no surface has STOP" if not stops else
                                            "STOP on surfaces " + ", ".join(str(s.number) for s in stops)))
    any_aspheric = False
    for s in lens:
        where = "%s:%d" % (path, s.line)
        medium = surface_medium(s, path, catalogues, info["gcat"])
        if medium.note:
            header.append("# Glass of " + medium.note + ".")
        if s.disz is None or math.isinf(s.disz):
            raise LensToolError("%s: surface %d has %s; every lens surface needs a finite DISZ"
                                % ("%s:%d" % (path, s.disz_line), s.number, "no DISZ" if s.disz is None else "DISZ INFINITY"))
        semi = s.clap if s.clap is not None else s.diam
        if semi is None or not semi > 0:
            raise LensToolError("%s: surface %d has no semi-diameter (DIAM > 0): the lens file needs each clear "
                                "aperture" % (where, s.number))
        if s.clap is not None:
            header.append("# Surface %d: its circular aperture CLAP (radius %s) is its clear aperture." % (s.number, fmt(s.clap)))
        # The even asphere's terms (PARM 1: r^2, refused; PARM 2..9: r^4..r^18), in mm.
        terms: List[float] = []
        for k, (value, line) in sorted(s.parm.items()):
            if value == 0:
                continue
            pwhere = "%s:%d" % (path, line)
            if s.type == "STANDARD":
                raise LensToolError("%s: PARM %d %s on surface %d: a STANDARD surface has no parameters"
                                    % (pwhere, k, fmt(value), s.number))
            if k == 1:
                raise LensToolError("%s: PARM 1 %s on surface %d (EVENASPH): the r^2 term is not represented (it "
                                    "duplicates the curvature); only PARM 2 .. %d (r^4 .. r^%d) may be non-zero"
                                    % (pwhere, fmt(value), s.number, MAX_EVENASPH_PARM, 2 * MAX_EVENASPH_PARM))
            if k > MAX_EVENASPH_PARM or k < 1:
                raise LensToolError("%s: PARM %d on surface %d (EVENASPH): the lens file holds the terms r^4 .. r^%d "
                                    "(PARM 2 .. %d)" % (pwhere, k, s.number, 2 * MAX_EVENASPH_PARM, MAX_EVENASPH_PARM))
            while len(terms) < k - 1:
                terms.append(0.0)
            terms[k - 2] = value * scale ** (1 - 2 * k)  # a_2k r^2k: length^(1 - 2k)
        radius = 0.0 if s.curv == 0 else 1 / s.curv * scale
        aspheric = s.conic != 0 or bool(terms)
        any_aspheric = any_aspheric or aspheric
        row: Dict[str, Any] = {"radius": radius, "thickness": s.disz * scale, "medium": medium,
               "aperture": 2 * semi * scale,
               "conic": s.conic, "terms": terms, "aspheric": aspheric, "stop": False, "surface": s.number,
               "line": s.line, "flat": s.curv == 0}
        if s.stop:
            stop_row: Dict[str, Any] = {"radius": 0.0, "thickness": 0.0, "aperture": 2 * semi * scale, "stop": True,
                        "aspheric": False, "surface": s.number, "line": s.line}
            same_medium = medium.nd == before.nd and medium.vd == before.vd
            if s.curv == 0 and same_medium and not aspheric:
                stop_row.update(thickness=s.disz * scale, medium=medium)
                rows.append(stop_row)
                header.append("# Surface %d is the stop." % s.number)
            elif s.curv >= 0:
                # The stop's plane at the vertex, in front of a surface that bulges away from it.
                stop_row["medium"] = before
                rows.extend([stop_row, row])
                header.append("# Surface %d is the stop and refracts: the stop is a row of its own, of thickness 0, at "
                              "its vertex, in front of it." % s.number)
            else:
                stop_row.update(thickness=row["thickness"], medium=medium)
                row["thickness"] = 0.0
                rows.extend([row, stop_row])
                header.append("# Surface %d is the stop and refracts: the stop is a row of its own, of thickness 0 from "
                              "its vertex, behind it." % s.number)
        else:
            rows.append(row)
        media.append(medium)
        before = medium
    if before.nd != 1:
        raise LensToolError("%s:%d: the image surface (SURF %d) is in glass; the lens must end in air"
                            % (path, image.line, image.number))
    dispersive = any(r["medium"].vd != 0 for r in rows)
    columns = dispersive or any_aspheric
    header.append("# Rows: radius, thickness, index n_d of the medium after the row, clear aperture diameter (mm)%s%s."
                  % (", V_d (0: none)" if columns else "",
                     "; on aspheric rows the conic constant and the even-asphere coefficients a4, a6, ... "
                     "(mm^-3, mm^-5, ...)" if any_aspheric else ""))
    header.append("# Flat refracting surfaces have radius %s (read as flat)." % FLAT_RADIUS
                  if any(r.get("flat") and not r["stop"] for r in rows) else "#")
    if header[-1] == "#":
        header.pop()
    lines = header[:]
    origins: Dict[int, Tuple[int, int]] = {}
    for r in rows:
        medium = r["medium"]
        ior = 1.0 if r["stop"] and medium.nd == 1 else medium.nd
        radius_text = "0" if r["stop"] else (FLAT_RADIUS if r["radius"] == 0 else fmt(r["radius"]))
        cells = [radius_text, fmt(r["thickness"]), fmt(ior), fmt(r["aperture"])]
        if columns:
            cells.append(fmt(0.0 if r["stop"] else medium.vd))
        if r["aspheric"]:
            cells.append(fmt(r["conic"]))
            cells.extend(fmt(a) for a in r["terms"])
        comment = "stop (SURF %d, line %d)" % (r["surface"], r["line"]) if r["stop"] else \
            "SURF %d, line %d" % (r["surface"], r["line"])
        lines.append("  ".join("%12s" % c for c in cells) + "    # " + comment)
        origins[len(lines)] = (r["surface"], r["line"])
    return Imported("\n".join(lines) + "\n", origins)


# ----------------------------------------------------------------------------------------------
# The optics core's answers (plenoptic-lens-data)
# ----------------------------------------------------------------------------------------------

def load_lens(path: str, catalogues: Sequence[str]) -> Tuple[str, str, Optional[Imported]]:
    """The lens file's text for `path` (a .zmx imported in memory), its display name, and the
    import (None for a lens file)."""
    if path.lower().endswith(".zmx"):
        text, encoding = read_text(path)
        imported = zmx_to_lens_file(text, path, encoding, catalogues)
        return imported.text, path, imported
    text, _ = read_text(path)
    return text, path, None


def lens_data(text: str, name: str, imported: Optional[Imported], fields: Sequence[float] = (),
              program: Optional[str] = None) -> Dict[str, Any]:
    """plenoptic-lens-data's JSON for the lens file text; its refusal as a LensToolError."""
    try:
        exe = find_lens_data(program)
    except FileNotFoundError as e:
        raise LensToolError(str(e))
    command = [exe, "--name", name]
    for f in fields:
        command += ["--field", repr(float(f))]
    command.append("-")
    try:
        done = subprocess.run(command, input=text.encode("utf-8"), capture_output=True, timeout=300)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise LensToolError("cannot run %s: %s" % (exe, e))
    if done.returncode == 1:
        error = json.loads(done.stdout.decode("utf-8"))["error"]
        line = error.get("line", 0)
        if imported is not None and line in imported.origins:
            surface, zline = imported.origins[line]
            raise LensToolError("%s:%d (SURF %d, imported as line %d of the lens file): %s"
                                % (name, zline, surface, line, error["message"]))
        raise LensToolError("%s%s: %s" % (name, ":%d" % line if line else "", error["message"]))
    if done.returncode != 0:
        raise LensToolError(done.stderr.decode("utf-8", "replace").strip().splitlines()[-1]
                            if done.stderr.strip() else "%s failed (status %d)" % (exe, done.returncode))
    return json.loads(done.stdout.decode("utf-8"))


def write_atomically(path: str, data: bytes) -> None:
    """Writes path through a temporary file in its folder, renamed over it: never half-written."""
    folder = os.path.dirname(os.path.abspath(path))
    try:
        fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".tmp", dir=folder)
    except OSError as e:
        raise LensToolError("%s: cannot write there (%s)" % (path, e.strerror or e))
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except OSError as e:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise LensToolError("%s: cannot write it (%s)" % (path, e.strerror or e))


# ----------------------------------------------------------------------------------------------
# info
# ----------------------------------------------------------------------------------------------

def info_document(data: Dict[str, Any]) -> Dict[str, Any]:
    """--json: the data without the drawing's profiles and rays."""
    out = {k: v for k, v in data.items() if k not in ("rays", "rays_start_z_mm")}
    out["surfaces"] = [{k: v for k, v in s.items() if k != "profile"} for s in data["surfaces"]]
    return out


def info_text(data: Dict[str, Any]) -> str:
    p = data["paraxial"]
    rows = data["surfaces"]
    out = ["lens %s: %d rows, the stop row %d" % (data["name"], len(rows), p["stop_row"])]
    if not p["valid"]:
        out.append("  no first-order data: the lens is afocal or its stop images nowhere")
        return "\n".join(out) + "\n"

    def line(label, text):
        out.append("  %-26s %s" % (label, text))

    line("effective focal length", "%.4f mm" % p["efl_mm"])
    line("back focal distance", "%.4f mm (rear vertex to rear focal point)" % p["bfd_mm"])
    line("front focal distance", "%.4f mm (front focal point to front vertex)" % p["ffd_mm"])
    line("principal planes", "front z %.4f mm, rear z %.4f mm" % (p["front_principal_z_mm"], p["rear_principal_z_mm"]))
    line("entrance pupil", "diameter %.4f mm at z %.4f mm" % (p["entrance_pupil_mm"], p["entrance_pupil_z_mm"]))
    line("exit pupil", "diameter %.4f mm at z %.4f mm" % (p["exit_pupil_mm"], p["exit_pupil_z_mm"]))
    line("stop", "diameter %.4f mm at z %.4f mm (row %d)" % (p["stop_mm"], p["stop_z_mm"], p["stop_row"]))
    line("f-number", "%.4f (the stop as written, object at infinity)" % p["f_number"])
    line("length", "front to rear vertex %.4f mm; to the paraxial focus %.4f mm"
         % (p["rear_vertex_z_mm"], p["rear_focal_z_mm"]))
    line("largest field", "%.2f deg half-angle (the chief ray passes every clear aperture)" % data["largest_field_deg"])
    chromatic = data.get("chromatic")
    if chromatic and chromatic.get("valid"):
        for l in chromatic["lines"]:
            line("%s line (%.4f nm)" % (l["line"], l["wavelength_nm"]),
                 "EFL %.4f mm, back focus %.4f mm" % (l["efl_mm"], l["bfd_mm"]))
        line("longitudinal colour", "%.4f mm (back focus at F minus at C)" % chromatic["longitudinal_colour_mm"])
    elif not data.get("dispersive"):
        line("colour", "none (no row carries an Abbe number)")
    out.append("  (z from the front vertex, +z towards the image; lengths in mm; paraxial at the d line)")
    return "\n".join(out) + "\n"


# ----------------------------------------------------------------------------------------------
# draw
# ----------------------------------------------------------------------------------------------

AXIAL_RAY = (0, 0, 255)
FIELD_RAYS = [(230, 0, 0), (0, 150, 0), (200, 0, 200), (230, 120, 0)]


def glass_fill(nd: float) -> Tuple[int, int, int]:
    """Lighter for a low index, darker for a high one."""
    t = max(0.0, min(1.0, (nd - 1.4) / 0.5))
    return (int(215 - 60 * t), int(230 - 50 * t), int(245 - 30 * t))


def draw_png(data: Dict[str, Any], size: Tuple[int, int]) -> bytes:
    from PIL import Image, ImageDraw, PngImagePlugin

    width, height = size
    rows = data["surfaces"]
    p = data["paraxial"]
    image_z = data["image_plane_z_mm"]
    z0 = data["rays_start_z_mm"]
    r_max = max(0.5 * s["aperture_mm"] for s in rows)
    zs = [pt[1] for s in rows for pt in s["profile"] if pt[1] is not None]
    z_lo = min([0.0] + zs)
    z_hi = max([image_z, rows[-1]["vertex_z_mm"]] + zs)
    image_heights = [abs(r["points"][-1][0]) for r in data["rays"] if r["result"] == "passed"]
    y_max = 1.15 * max([r_max] + image_heights)
    # Some room in front of the lens for the incoming rays, a little behind the image plane.
    span = z_hi - z_lo
    z_left = max(z0, z_lo - 0.12 * span)
    z_right = z_hi + 0.04 * span
    margin = 12
    scale = min((width - 2 * margin) / (z_right - z_left), (height - 2 * margin - 14) / (2 * y_max))
    x_off = margin + 0.5 * ((width - 2 * margin) - scale * (z_right - z_left)) - scale * z_left
    axis_row = float((height - 14) // 2)

    def px(y, z):
        # A point within a quarter pixel of the axis is drawn on it (the axial chief ray, aimed a
        # hair off the axis, would otherwise wander between two rows).
        return (x_off + scale * z, axis_row - (scale * y if abs(scale * y) >= 0.25 else 0.0))

    picture = Image.new("RGB", (width, height), (255, 255, 255))
    d = ImageDraw.Draw(picture)
    # Glass: between a refracting row and the next, joined at the rims (the wider rim reached by
    # a step, as element drawings show the edge).
    for i, s in enumerate(rows[:-1]):
        nxt = rows[i + 1]
        if s["stop"] or nxt["stop"] or s["ior"] <= 1.0 or not s["profile"] or not nxt["profile"]:
            continue
        a, b = s["profile"], nxt["profile"]
        if any(pt[1] is None for pt in a + b):
            continue
        edge = max(abs(a[0][0]), abs(b[0][0]))
        za_top, zb_top = a[-1][1], b[-1][1]
        za_bot, zb_bot = a[0][1], b[0][1]
        polygon = [px(r, z) for r, z in a]
        polygon += [px(edge, za_top), px(edge, zb_top)]
        polygon += [px(r, z) for r, z in reversed(b)]
        polygon += [px(-edge, zb_bot), px(-edge, za_bot)]
        d.polygon(polygon, fill=glass_fill(s["ior"]), outline=(70, 70, 70))
    for s in rows:
        if s["profile"] and all(pt[1] is not None for pt in s["profile"]):
            d.line([px(r, z) for r, z in s["profile"]], fill=(40, 40, 40), width=1)
    # The axis (dashed), the stop, the image plane.
    x_a, _ = px(0, z_left)
    x_b, _ = px(0, z_right)
    x = x_a
    while x < x_b:
        d.line([(x, axis_row), (min(x + 8, x_b), axis_row)], fill=(150, 150, 150))
        x += 12
    stop = rows[p["stop_row"] - 1]
    r_stop = 0.5 * stop["aperture_mm"]
    # The stop's blades reach out to the wider of its neighbours' rims (at least a quarter of the
    # opening beyond its edge).
    i_stop = p["stop_row"] - 1
    neighbours = [0.5 * rows[j]["aperture_mm"] for j in (i_stop - 1, i_stop + 1) if 0 <= j < len(rows)]
    r_out = max([r_stop * 1.25] + [1.08 * r for r in neighbours])
    for sign in (1, -1):
        d.line([px(sign * r_stop, stop["vertex_z_mm"]), px(sign * r_out, stop["vertex_z_mm"])], fill=(0, 0, 0), width=3)
    if p["valid"]:
        d.line([px(y_max / 1.15, image_z), px(-y_max / 1.15, image_z)], fill=(90, 90, 90), width=1)
    # The rays: the axis's in blue, each field's in its own colour.
    fields = sorted({r["field_deg"] for r in data["rays"]}, key=abs)
    for r in data["rays"]:
        colour = AXIAL_RAY if r["field_deg"] == 0 else FIELD_RAYS[(fields.index(r["field_deg"]) - 1) % len(FIELD_RAYS)]
        if r["result"] != "passed":
            colour = (int(colour[0] + 0.55 * (255 - colour[0])), int(colour[1] + 0.55 * (255 - colour[1])),
                      int(colour[2] + 0.55 * (255 - colour[2])))  # a blocked ray, paler
        points = [px(y, z) for y, z in r["points"]]
        d.line(points, fill=colour, width=1)
        if r["result"] != "passed" and len(points) > 1:
            x, y = points[-1]
            d.line([(x - 3, y - 3), (x + 3, y + 3)], fill=colour, width=2)
            d.line([(x - 3, y + 3), (x + 3, y - 3)], fill=colour, width=2)
    caption = "%s   EFL %.2f mm   f/%.2f   fields %s deg" % (
        os.path.basename(data["name"]), p["efl_mm"], p["f_number"],
        ", ".join("%g" % f for f in fields))
    d.rectangle([(0, height - 16), (width, height)], fill=(255, 255, 255))
    d.text((margin, height - 14), caption, fill=(0, 0, 0))
    # The drawing's frame, for scripts (and the tests): pixel x = x0 + mm_per... as PNG text.
    meta = PngImagePlugin.PngInfo()
    meta.add_text("plenoptic-lens frame", json.dumps(
        {"px_per_mm": scale, "x_of_z0": x_off, "axis_row": axis_row,
         "note": "pixel (x, row) of lens point (y, z) mm: x = x_of_z0 + px_per_mm z, row = axis_row - px_per_mm y"}))
    import io
    buffer = io.BytesIO()
    picture.save(buffer, format="PNG", pnginfo=meta)
    return buffer.getvalue()


# ----------------------------------------------------------------------------------------------
# The command
# ----------------------------------------------------------------------------------------------

def parse_size(text: str) -> Tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise LensToolError("--size %s: want WIDTHxHEIGHT in pixels, e.g. 1200x600" % text)
    if not (100 <= w <= 20000 and 100 <= h <= 20000):
        raise LensToolError("--size %s: each side from 100 to 20000 pixels" % text)
    return w, h


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="plenoptic-lens", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--catalogue", action="append", default=[], metavar="FILE.agf",
                        help="a Zemax AGF glass catalogue holding the .zmx file's catalogue glasses (repeatable)")
    common.add_argument("--lens-data", default=None, help="the plenoptic-lens-data program (default: found beside "
                        "the package, in the build tree, or on PATH)")
    q = sub.add_parser("import", parents=[common], help="a Zemax .zmx file -> a lens file")
    q.add_argument("lens", help="LENS.zmx")
    q.add_argument("-o", "--output", required=True, help="the lens file to write (pbrt's rows)")
    q = sub.add_parser("info", parents=[common], help="first-order data and colour")
    q.add_argument("lens", help="a lens file, or a .zmx")
    q.add_argument("--json", action="store_true", help="machine-readable output")
    q = sub.add_parser("draw", parents=[common], help="a drawing of the lens with traced rays")
    q.add_argument("lens", help="a lens file, or a .zmx")
    q.add_argument("-o", "--output", required=True, help="the PNG to write")
    q.add_argument("--field", type=float, action="append", default=None, metavar="DEG",
                   help="a field angle (degrees) whose chief and marginal rays are drawn beside the axis's "
                        "(repeatable; default: the largest field whose chief ray passes; 0: the axis only)")
    q.add_argument("--size", default="1200x600", help="WIDTHxHEIGHT in pixels (default 1200x600)")
    args = p.parse_args(argv)
    try:
        if args.command == "import":
            if not args.lens.lower().endswith(".zmx"):
                raise LensToolError("%s: import reads a Zemax sequential file (.zmx)" % args.lens)
            text, encoding = read_text(args.lens)
            converted = zmx_to_lens_file(text, args.lens, encoding, args.catalogue)
            # The lens as the camera will read it: refused here rather than at render time.
            lens_data(converted.text, args.lens, converted, program=args.lens_data)
            write_atomically(args.output, converted.text.encode("utf-8"))
            return 0
        text, name, imported = load_lens(args.lens, args.catalogue)
        if args.command == "info":
            data = lens_data(text, name, imported, program=args.lens_data)
            sys.stdout.write(json.dumps(info_document(data), indent=1) + "\n" if args.json else info_text(data))
            return 0
        size = parse_size(args.size)
        if not args.output.lower().endswith(".png"):
            raise LensToolError("%s: draw writes a PNG (-o NAME.png)" % args.output)
        fields = args.field
        for f in fields or []:
            if not -90 < f < 90:
                raise LensToolError("--field %g: a field angle in degrees, above -90 and below 90" % f)
        if fields is None:
            first = lens_data(text, name, imported, program=args.lens_data)
            fields = [math.floor(first["largest_field_deg"] * 10) / 10]
        data = lens_data(text, name, imported, fields, program=args.lens_data)
        write_atomically(args.output, draw_png(data, size))
        return 0
    except LensToolError as e:
        print("plenoptic-lens: %s" % e, file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
