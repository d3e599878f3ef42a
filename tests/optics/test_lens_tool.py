# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-lens (python/plenoptic_lf/lens_tool.py, with source/tools/plenoptic_lens_data.cpp):
import of Zemax .zmx files written here from designs whose numbers the test knows, info against
the test's own paraxial (y-nu) trace, refusals by name and line, the drawing's rays where the
test computes they must be, and a round trip of the catalogue's Laikin wide angle.

Nothing is rendered. The .zmx text is written by the test in the plain layout such files have
(SURF blocks of indented keywords); the glass catalogue is a small AGF written here with SCHOTT's
published Sellmeier coefficients of N-BK7 and N-F2 (the figures are stated below).
"""
import json
import math
import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
LAIKIN = os.path.join(SOURCE, "lenses", "wide_angle_22mm_laikin_f3.5.dat")

# SCHOTT's published data (optical glass data sheets): Sellmeier B1, B2, B3, C1, C2, C3 (C in µm²),
# and the catalogue's n_d and V_d.
N_BK7 = dict(b=(1.03961212, 0.231792344, 1.01046945), c=(0.00600069867, 0.0200179144, 103.560653),
             nd=1.51680, vd=64.17)
N_F2 = dict(b=(1.39757037, 0.159201403, 1.26865430), c=(0.00995906143, 0.0546931752, 119.248346),
            nd=1.62005, vd=36.43)
LINES_UM = {"F": 0.4861327, "d": 0.5875618, "C": 0.6562725}


def agf(glasses):
    """A catalogue in Zemax's AGF layout: NM name formula MIL N(d) V(d) ...; CD coefficients."""
    out = ["CC test catalogue written by test_lens_tool.py"]
    for name, g in glasses.items():
        out.append("NM %s 2 0 %.5f %.2f 0 0 0" % (name, g["nd"], g["vd"]))
        out.append("CD %s 0 0 0 0" % " ".join("%.9g %.9g" % (b, c) for b, c in zip(g["b"], g["c"])))
    return "\r\n".join(out) + "\r\n"


def sellmeier(g, um):
    l2 = um * um
    return math.sqrt(1 + sum(b * l2 / (l2 - c) for b, c in zip(g["b"], g["c"])))


def two_term(nd, vd, nm):
    """The lens file's dispersion model (docs/real-lenses.md, glass.h), written here again."""
    return nd if vd == 0 else nd + (nd - 1) / vd * (523655 / nm ** 2 - 1.5168)


def y_nu(rows, index=lambda row: row[2]):
    """The test's own paraxial trace of lens-file rows (radius, thickness, n, ...; radius 0 the
    stop, |radius| > 1e12 flat): EFL and back focal distance for an object at infinity."""
    y, nu, n = 1.0, 0.0, 1.0
    for i, row in enumerate(rows):
        radius = row[0]
        n2 = n if radius == 0 else index(row)
        if radius != 0 and abs(radius) < 1e12:
            nu = nu - y * (n2 - n) / radius
        n = n2
        if i < len(rows) - 1:
            y = y + row[1] * nu / n
    efl = -1 / nu
    return efl, -y / nu


def zmx(surfaces, unit="MM", extra_header=()):
    """A .zmx text: the object at infinity, the surfaces (dicts of keyword -> value text), the image."""
    out = ["VERS 190513 80 123457 L123457", "MODE SEQ", "NAME test lens", "UNIT %s X W X CM MR CPMM" % unit,
           "ENPD 10"] + list(extra_header)
    out += ["SURF 0", "  TYPE STANDARD", "  CURV 0.0 0 0 0 0 \"\"", "  DISZ INFINITY"]
    for k, s in enumerate(surfaces, 1):
        out.append("SURF %d" % k)
        if s.get("stop"):
            out.append("  STOP")
        out.append("  TYPE %s" % s.get("type", "STANDARD"))
        out.append("  CURV %s 0 0 0 0 \"\"" % s.get("curv", "0"))
        for key in ("CONI", "GLAS"):
            if key.lower() in s:
                out.append("  %s %s" % (key, s[key.lower()]))
        for n, v in s.get("parm", []):
            out.append("  PARM %d %s" % (n, v))
        out.append("  DISZ %s" % s["disz"])
        out.append("  DIAM %s 1 0 0 1 \"\"" % s["diam"])
        out.extend(s.get("lines", []))
    out += ["SURF %d" % (len(surfaces) + 1), "  TYPE STANDARD", "  CURV 0", "  DISZ 0"]
    return "\r\n".join(out) + "\r\n"


def model(nd, vd):
    return "___BLANK 1 0 %r %r 0 0 0 0 0 0" % (nd, vd)


# The singlet: a stop 5 mm in front of an equiconvex N-BK7-like lens (model glass), f about 50.
SINGLET = [dict(stop=True, disz="5", diam="5"),
           dict(curv=repr(1 / 51.5), disz="4", glas=model(1.5168, 64.17), diam="8"),
           dict(curv=repr(-1 / 51.5), disz="95", diam="8")]
SINGLET_ROWS = [[0, 5, 1, 10, 0], [51.5, 4, 1.5168, 16, 64.17], [-51.5, 95, 1, 16, 0]]


def data_rows(text):
    """The numbers of a lens file's rows."""
    rows = []
    for line in text.splitlines():
        line = line.split("#")[0].split()
        if line:
            rows.append([float(v) for v in line])
    return rows


def same_rows(got, want, rel=1e-9):
    assert len(got) == len(want), "rows:\n%s\nwant:\n%s" % (got, want)
    for g, w in zip(got, want):
        assert len(g) == len(w), "row %s, want %s" % (g, w)
        for a, b in zip(g, w):
            assert a == pytest.approx(b, rel=rel, abs=1e-12), "row %s, want %s" % (g, w)


@pytest.fixture(scope="module")
def tool(args):
    lens_data = os.path.abspath(args.lens_data)
    assert os.path.isfile(lens_data), "plenoptic-lens-data not built: %s" % lens_data
    launcher = os.path.join(args.tools, "plenoptic-lens")

    def run(*argv, expect=0):
        r = subprocess.run(["/usr/bin/python3", launcher] + [str(a) for a in argv] + ["--lens-data", lens_data],
                           capture_output=True, text=True, timeout=120, cwd=args.work)
        assert "Traceback" not in r.stderr, r.stderr
        if expect is not None:
            assert r.returncode == expect, "plenoptic-lens %s: status %d\n%s%s" % (
                " ".join(map(str, argv)), r.returncode, r.stdout[-2000:], r.stderr[-2000:])
        return r
    return run


def write(path, text, encoding="utf-8"):
    with open(path, "wb") as f:
        if encoding == "utf-16":
            f.write(b"\xff\xfe" + text.encode("utf-16-le"))
        elif encoding == "utf-8-bom":
            f.write(b"\xef\xbb\xbf" + text.encode("utf-8"))
        else:
            f.write(text.encode(encoding))
    return path


@pytest.mark.parametrize("encoding", ["utf-8", "utf-8-bom", "utf-16"])
def test_singlet_import_and_info(args, tool, encoding):
    src = write(os.path.join(args.work, "singlet-%s.zmx" % encoding), zmx(SINGLET), encoding)
    out = os.path.join(args.work, "singlet-%s.dat" % encoding)
    tool("import", src, "-o", out)
    with open(out) as f:
        text = f.read()
    same_rows(data_rows(text), SINGLET_ROWS)
    assert ("UTF-16 LE" if encoding == "utf-16" else "UTF-8") in text.splitlines()[0]
    info = json.loads(tool("info", src, "--json").stdout)
    efl, bfd = y_nu(SINGLET_ROWS)
    assert info["paraxial"]["efl_mm"] == pytest.approx(efl, rel=1e-10)
    assert info["paraxial"]["bfd_mm"] == pytest.approx(bfd, rel=1e-10)
    # The lensmaker's thick-lens formula too: 1/f = (n - 1) (2/R - (n - 1) t / (n R^2)).
    n, R, t = 1.5168, 51.5, 4.0
    assert info["paraxial"]["efl_mm"] == pytest.approx(1 / ((n - 1) * (2 / R - (n - 1) * t / (n * R * R))), rel=1e-10)
    # The stop in front: the entrance pupil is the stop itself; f-number EFL / 10.
    assert info["paraxial"]["entrance_pupil_mm"] == pytest.approx(10, rel=1e-12)
    assert info["paraxial"]["f_number"] == pytest.approx(efl / 10, rel=1e-10)
    # Longitudinal colour: the test's trace at the F and C lines with the two-term model.
    focus = {line: y_nu(SINGLET_ROWS, lambda row, nm=um * 1000: two_term(row[2], row[4], nm))[1]
             for line, um in LINES_UM.items()}
    assert info["chromatic"]["longitudinal_colour_mm"] == pytest.approx(focus["F"] - focus["C"], abs=1e-9)
    text_info = tool("info", out).stdout
    assert "effective focal length" in text_info and "%.4f mm" % efl in text_info
    assert "longitudinal colour" in text_info


def test_units_inches(args, tool):
    inch = [dict(stop=True, disz=repr(5 / 25.4), diam=repr(5 / 25.4)),
            dict(curv=repr(25.4 / 51.5), disz=repr(4 / 25.4), glas=model(1.5168, 64.17), diam=repr(8 / 25.4)),
            dict(curv=repr(-25.4 / 51.5), disz=repr(95 / 25.4), diam=repr(8 / 25.4))]
    src = write(os.path.join(args.work, "singlet-inch.zmx"), zmx(inch, unit="IN"))
    out = os.path.join(args.work, "singlet-inch.dat")
    tool("import", src, "-o", out)
    with open(out) as f:
        same_rows(data_rows(f.read()), SINGLET_ROWS, rel=1e-8)


def achromat_design():
    """A cemented N-BK7 / N-F2 achromat of f = 100 mm from the thin-lens achromat conditions
    (phi1 = phi V1 / (V1 - V2), phi2 = -phi V2 / (V1 - V2)), the crown equiconvex, with the
    catalogue's figures; thicknesses 5 and 2.5 mm, stop 20 mm at the front vertex."""
    phi = 1 / 100.0
    v1, v2 = N_BK7["vd"], N_F2["vd"]
    phi1, phi2 = phi * v1 / (v1 - v2), -phi * v2 / (v1 - v2)
    c1 = phi1 / (2 * (N_BK7["nd"] - 1))
    c2 = -c1
    c3 = c2 - phi2 / (N_F2["nd"] - 1)
    return c1, c2, c3


def test_achromat_from_catalogue(args, tool):
    cat = write(os.path.join(args.work, "test-glass.agf"), agf({"N-BK7": N_BK7, "N-F2": N_F2}), "utf-16")
    c1, c2, c3 = achromat_design()
    surfaces = [dict(stop=True, disz="0", diam="10"),
                dict(curv=repr(c1), disz="5", glas="N-BK7 0 0 1.5168 64.17 0 0 0 0 0 0", diam="12"),
                dict(curv=repr(c2), disz="2.5", glas="N-F2 0 0 1.62 36.37 0 0 0 0 0 0", diam="12"),
                dict(curv=repr(c3), disz="95", diam="12")]
    src = write(os.path.join(args.work, "achromat.zmx"), zmx(surfaces, extra_header=["GCAT SCHOTT"]))
    out = os.path.join(args.work, "achromat.dat")
    if os.path.exists(out):
        os.unlink(out)
    r = tool("import", src, "-o", out, expect=2)
    assert "N-BK7" in r.stderr and "achromat.zmx:" in r.stderr and "--catalogue" in r.stderr, r.stderr
    assert not os.path.exists(out)
    tool("import", src, "-o", out, "--catalogue", cat)
    with open(out) as f:
        text = f.read()
    rows = data_rows(text)
    # n_d and V_d from the Sellmeier terms at the lines, computed here; and against SCHOTT's
    # printed n_d (5 decimals) and V_d (2 decimals).
    for row, g in ((rows[1], N_BK7), (rows[2], N_F2)):
        nd, nf, nc = (sellmeier(g, LINES_UM[k]) for k in "dFC")
        assert row[2] == pytest.approx(nd, abs=1e-9) and row[4] == pytest.approx((nd - 1) / (nf - nc), abs=1e-6)
        assert abs(row[2] - g["nd"]) < 2e-5 and abs(row[4] - g["vd"]) < 0.02, (row, g)
    same_rows([r[:2] + r[3:4] for r in rows],
              [[0, 0, 20], [1 / c1, 5, 24], [1 / c2, 2.5, 24], [1 / c3, 95, 24]])
    info = json.loads(tool("info", out, "--json").stdout)
    efl, _ = y_nu(rows)
    assert info["paraxial"]["efl_mm"] == pytest.approx(efl, rel=1e-10)
    focus = {line: y_nu(rows, lambda row, nm=um * 1000: two_term(row[2], row[4], nm))[1]
             for line, um in LINES_UM.items()}
    achromat = info["chromatic"]["longitudinal_colour_mm"]
    assert achromat == pytest.approx(focus["F"] - focus["C"], abs=1e-9)
    # A singlet of N-BK7 of the same focal length: colour about f / V_d; the achromat far less.
    assert abs(achromat) < 0.1 * efl / N_BK7["vd"], (achromat, efl / N_BK7["vd"])


def test_evenasph_rows(args):
    """EVENASPH: CONI and PARM 2.. become columns 6.. (conic, a4, a6, ...), in mm; checked on the
    conversion itself (the render path's reading of the aspheric columns is tested beside it)."""
    sys.path.insert(0, args.python)
    from plenoptic_lf.lens_tool import LensToolError, zmx_to_lens_file
    surfaces = [dict(stop=True, disz="2", diam="5"),
                dict(type="EVENASPH", curv=repr(1 / 40.0), coni="-0.8", parm=[(1, "0"), (2, "1.5e-06"), (3, "-2e-09")],
                     disz="6", glas=model(1.58, 30.0), diam="9"),
                dict(curv=repr(-1 / 200.0), disz="60", diam="9")]
    lens = zmx_to_lens_file(zmx(surfaces), "asph.zmx")
    same_rows(data_rows(lens.text), [[0, 2, 1, 10, 0], [40, 6, 1.58, 18, 30, -0.8, 1.5e-6, -2e-9],
                                     [-200, 60, 1, 18, 0]])
    # The same in inches: a_2k scales as length^(1 - 2k).
    inch = [dict(stop=True, disz=repr(2 / 25.4), diam=repr(5 / 25.4)),
            dict(type="EVENASPH", curv=repr(25.4 / 40.0), coni="-0.8",
                 parm=[(2, repr(1.5e-6 * 25.4 ** 3)), (3, repr(-2e-9 * 25.4 ** 5))],
                 disz=repr(6 / 25.4), glas=model(1.58, 30.0), diam=repr(9 / 25.4)),
            dict(curv=repr(-25.4 / 200.0), disz=repr(60 / 25.4), diam=repr(9 / 25.4))]
    same_rows(data_rows(zmx_to_lens_file(zmx(inch, unit="IN"), "asph-in.zmx").text),
              [[0, 2, 1, 10, 0], [40, 6, 1.58, 18, 30, -0.8, 1.5e-6, -2e-9], [-200, 60, 1, 18, 0]], rel=1e-8)
    surfaces[1]["parm"] = [(1, "0.001")]
    with pytest.raises(LensToolError, match=r"asph\.zmx:\d+: PARM 1"):
        zmx_to_lens_file(zmx(surfaces), "asph.zmx")


def line_of(text, needle, after=0):
    for n, line in enumerate(text.splitlines(), 1):
        if n > after and needle in line:
            return n
    raise AssertionError(needle)


REFUSALS = [
    # (name, how the singlet's text is changed, keyword the message names, the line's text)
    ("coordinate break", lambda t: t.replace("SURF 3\r\n  TYPE STANDARD", "SURF 3\r\n  TYPE COORDBRK"), "COORDBRK",
     "TYPE COORDBRK"),
    ("mirror", lambda t: t.replace("GLAS " + model(1.5168, 64.17), "GLAS MIRROR 0 0"), "MIRROR", "GLAS MIRROR"),
    ("gradient index", lambda t: t.replace("SURF 2\r\n  TYPE STANDARD", "SURF 2\r\n  TYPE GRINSUR"), "gradient",
     "TYPE GRINSUR"),
    ("toroidal", lambda t: t.replace("SURF 2\r\n  TYPE STANDARD", "SURF 2\r\n  TYPE TOROIDAL"), "TOROIDAL",
     "TYPE TOROIDAL"),
    ("even asphere r^2", lambda t: t.replace("SURF 2\r\n  TYPE STANDARD", "SURF 2\r\n  TYPE EVENASPH\r\n  PARM 1 0.002"),
     "PARM 1", "PARM 1 0.002"),
    ("parameter on a standard surface", lambda t: t.replace("SURF 2\r\n  TYPE STANDARD",
                                                            "SURF 2\r\n  TYPE STANDARD\r\n  PARM 3 0.5"),
     "PARM 3", "PARM 3 0.5"),
    ("unit", lambda t: t.replace("UNIT MM", "UNIT FT"), "UNIT", "UNIT FT"),
    ("non-sequential", lambda t: t.replace("MODE SEQ", "MODE NSC"), "MODE", "MODE NSC"),
    ("unknown surface keyword (a tilt)", lambda t: t.replace("SURF 3\r\n", "SURF 3\r\n  TILT 0 5 0\r\n"), "TILT",
     "TILT 0 5"),
    ("two configurations", lambda t: t.replace("ENPD 10", "ENPD 10\r\nMNUM 2 1"), "MNUM", "MNUM 2"),
    ("annular aperture", lambda t: t.replace("SURF 3\r\n", "SURF 3\r\n  CLAP 1 8 0\r\n"), "CLAP", "CLAP 1 8"),
]


@pytest.mark.parametrize("name,change,keyword,needle", REFUSALS, ids=[r[0] for r in REFUSALS])
def test_refusals(args, tool, name, change, keyword, needle):
    text = change(zmx(SINGLET))
    assert text != zmx(SINGLET)
    src = write(os.path.join(args.work, "refused.zmx"), text)
    out = os.path.join(args.work, "refused.dat")
    with open(out, "w") as f:
        f.write("kept\n")
    r = tool("import", src, "-o", out, expect=2)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("plenoptic-lens: %s:%d:" % (src, line_of(text, needle))), (lines[0], needle)
    assert keyword in lines[0], lines[0]
    with open(out) as f:
        assert f.read() == "kept\n", "a refused import left its output untouched"
    assert not [n for n in os.listdir(args.work) if n.startswith(".refused.dat")], "no temporary file left"


def test_no_stop_refused(args, tool):
    surfaces = [dict(s) for s in SINGLET]
    surfaces[0].pop("stop")
    src = write(os.path.join(args.work, "nostop.zmx"), zmx(surfaces))
    r = tool("import", src, "-o", os.path.join(args.work, "nostop.dat"), expect=2)
    assert "STOP" in r.stderr and "exactly one stop" in r.stderr


def test_draw_rays(args, tool):
    """A slow singlet (f/10): the axial marginal rays' pixels meet on the axis at the paraxial focus
    the test computes, and span the stop's diameter at the stop."""
    from PIL import Image
    slow = [dict(s) for s in SINGLET]
    slow[0]["diam"] = "2.5"
    src = write(os.path.join(args.work, "slow.zmx"), zmx(slow))
    png = os.path.join(args.work, "slow.png")
    tool("draw", src, "-o", png, "--size", "900x420", "--field", "4")
    image = Image.open(png)
    assert image.size == (900, 420)
    frame = json.loads(image.text["plenoptic-lens frame"])
    pixels = image.convert("RGB").load()
    scale, x0, axis = frame["px_per_mm"], frame["x_of_z0"], frame["axis_row"]
    rows = [[0, 5, 1, 5, 0]] + SINGLET_ROWS[1:]
    _, bfd = y_nu(rows)
    focus_z = 5 + 4 + bfd

    def blue_extent(col):
        rows_ = [j for j in range(image.size[1]) if pixels[col, j] == (0, 0, 255)]
        return (min(rows_), max(rows_)) if rows_ else None

    # The upper marginal ray behind the lens: the top blue pixel of each column where the rays are
    # well apart, a straight line in the picture; where it meets the axis row.
    lens_back = int(x0 + scale * 12)
    cols, tops = [], []
    for c in range(lens_back, int(x0 + scale * focus_z)):
        e = blue_extent(c)
        if e and e[1] - e[0] > 12:
            cols.append(c)
            tops.append(e[0])
    assert len(cols) > 50
    n = len(cols)
    mc, mt = sum(cols) / n, sum(tops) / n
    slope = sum((c - mc) * (r - mt) for c, r in zip(cols, tops)) / sum((c - mc) ** 2 for c in cols)
    crossing = mc + (axis - mt) / slope
    # Spherical aberration of this f/10 singlet moves the marginal focus by about 0.1 mm; with
    # the pixels' rounding, within 2 px + 0.3 mm of the paraxial focus.
    assert abs(crossing - (x0 + scale * focus_z)) <= 2 + 0.3 * scale, (crossing, x0 + scale * focus_z, scale)
    # At the stop (z = 0) the marginal rays are at +-1.25 mm... just behind it, since the stop's
    # own black bar covers its column.
    col = int(round(x0 + scale * 0.6))
    top, bottom = blue_extent(col)
    assert abs((bottom - top) - 2 * 2.5 * scale) <= 3, (bottom - top, 2 * 2.5 * scale)
    assert abs(0.5 * (top + bottom) - axis) <= 1.5
    # The field's rays (red) reach the image plane above the axis by about f tan(4 deg).
    efl, _ = y_nu(rows)
    col = int(round(x0 + scale * focus_z)) - 2
    red = [j for j in range(image.size[1]) if pixels[col, j] == (230, 0, 0)]
    assert red, "no field ray at the image plane"
    height = (axis - sum(red) / len(red)) / scale
    assert height == pytest.approx(efl * math.tan(math.radians(4)), rel=0.05), height


def test_draw_refusals(args, tool):
    out = os.path.join(args.work, "bad.png")
    r = tool("draw", LAIKIN, "-o", out, "--size", "20x20", expect=2)
    assert "--size" in r.stderr and not os.path.exists(out)
    r = tool("draw", LAIKIN, "-o", out, "--field", "95", expect=2)
    assert "--field" in r.stderr and not os.path.exists(out)
    r = tool("info", os.path.join(args.work, "missing.dat"), expect=2)
    assert "missing.dat" in r.stderr


def test_laikin_round_trip(args, tool):
    """The catalogue's Laikin wide angle written as a .zmx (its stop a flat STOP surface, each glass
    a model glass of the row's index) and imported back equals the lens file's rows; info of both
    agrees."""
    with open(LAIKIN) as f:
        rows = data_rows(f.read())
    surfaces, before = [], 1.0
    for r in rows:
        s = dict(curv=repr(0.0 if r[0] == 0 else 1 / r[0]), disz=repr(r[1]), diam=repr(r[3] / 2))
        if r[0] == 0:
            s["stop"] = True
        if r[2] != 1:
            s["glas"] = model(r[2], 0.0)
        surfaces.append(s)
    src = write(os.path.join(args.work, "laikin.zmx"), zmx(surfaces), "utf-16")
    out = os.path.join(args.work, "laikin.dat")
    tool("import", src, "-o", out)
    with open(out) as f:
        same_rows(data_rows(f.read()), rows)
    a = json.loads(tool("info", LAIKIN, "--json").stdout)["paraxial"]
    b = json.loads(tool("info", src, "--json").stdout)["paraxial"]
    for key in ("efl_mm", "bfd_mm", "entrance_pupil_mm", "exit_pupil_z_mm", "f_number"):
        assert b[key] == pytest.approx(a[key], rel=1e-9), key
    efl, bfd = y_nu(rows)
    assert a["efl_mm"] == pytest.approx(efl, rel=1e-10) and a["bfd_mm"] == pytest.approx(bfd, rel=1e-10)
    png = os.path.join(args.work, "laikin.png")
    tool("draw", LAIKIN, "-o", png)
    from PIL import Image
    assert Image.open(png).size == (1200, 600)


def test_stop_on_refracting_surface(args, tool):
    """STOP on a convex front surface: a stop row of thickness 0 in front of it; on a rear surface
    of negative radius: behind it, taking the surface's thickness. Either way the paraxial data
    equal the test's trace of the expected rows, the stop's diameter the surface's aperture."""
    front = [dict(stop=True, curv=repr(1 / 51.5), disz="4", glas=model(1.5168, 64.17), diam="5"),
             dict(curv=repr(-1 / 51.5), disz="95", diam="8")]
    rear = [dict(curv=repr(1 / 51.5), disz="4", glas=model(1.5168, 64.17), diam="8"),
            dict(stop=True, curv=repr(-1 / 51.5), disz="95", diam="5")]
    want = {"front": [[0, 0, 1, 10, 0], [51.5, 4, 1.5168, 10, 64.17], [-51.5, 95, 1, 16, 0]],
            "rear": [[51.5, 4, 1.5168, 16, 64.17], [-51.5, 0, 1, 10, 0], [0, 95, 1, 10, 0]]}
    for name, surfaces in (("front", front), ("rear", rear)):
        src = write(os.path.join(args.work, "stop-%s.zmx" % name), zmx(surfaces))
        out = os.path.join(args.work, "stop-%s.dat" % name)
        tool("import", src, "-o", out)
        with open(out) as f:
            same_rows(data_rows(f.read()), want[name])
        info = json.loads(tool("info", out, "--json").stdout)
        efl, bfd = y_nu(want[name])
        assert info["paraxial"]["efl_mm"] == pytest.approx(efl, rel=1e-10)
        assert info["paraxial"]["bfd_mm"] == pytest.approx(bfd, rel=1e-10)
        assert info["paraxial"]["stop_mm"] == 10
