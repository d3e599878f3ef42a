# SPDX-License-Identifier: AGPL-3.0-or-later
"""Microlens arrays with manufacturing errors, fill factors and masks, rendered (docs/camera.md,
"Real microlens arrays").

- Jittered lenses: each microimage's centroid in a white world, measured on the rendered image,
  must lie within 0.05 px of the truth the render writes (microimages.csv) and of the independent
  answer: the central projection of the displaced lens centre (the CSV's dx_mm, dy_mm added to the
  lattice point written out here) from the thin main lens's centre onto the sensor. The lenses
  really move (the truth leaves the lattice by more than the tolerance).
- A lens table made of that CSV gives the same render (the truth reads back as the array).
- Energy: a white world through a masked array delivers the fill factor's share of the light of
  the ideal array (the lens part of the array's area); through clear gaps all of it.
- Refracting lenses with errors, their truth corrected from Jacobian anchors
  (`microimage_error_anchors`), against the same lenses measured each.
"""
import math
import os

import numpy as np

import plenoptic_testing as pt

W, H = 200, 150
PIXEL = 0.01            # mm
PITCH, F_MICRO = 0.15, 0.6
FOCAL, FOCUS_MM = 25.0, 2000.0
D = FOCAL * FOCUS_MM / (FOCUS_MM - FOCAL)  # thin-lens conjugate: the array's distance


def scene(f_number, array_extra, extra="samples 64"):
    return (pt.WORLD_HEADER + "background { rgb 1 }\n"
            "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n"
            "  main_lens { thin_lens focal_length %r f_number %r focus_distance 2 }\n"
            "  microlens_array { hexagonal pitch %r focal_length %r distance %r %s }\n"
            "  sensor { pixel_size %r }\n  %s\n}\n"
            % (FOCAL, f_number, PITCH, F_MICRO, F_MICRO, array_extra, PIXEL, extra))


def render(args, name, text):
    work = os.path.join(args.work, "array_errors")
    path = pt.render(args.povray, work, name, text, W, H)
    return path, work


def projected_centre_px(k, l, dx, dy):
    """Pixel (centre convention) of the displaced lens centre projected from the main lens's centre."""
    x = (k + (l % 2) / 2.0) * PITCH + dx
    y = l * PITCH * math.sqrt(3) / 2 + dy
    scale = (D + F_MICRO) / D
    return W / 2.0 - 0.5 - x * scale / PIXEL, H / 2.0 - 0.5 + y * scale / PIXEL


def component_centroids(image):
    """Centroid (u, v) and summed value of each lit microimage not touching the picture's edge."""
    value = image[..., :3].mean(axis=2)
    labels, count = pt.label_components(value > 0, connectivity=8)
    out = []
    vv, uu = np.mgrid[0:H, 0:W]
    for index in range(1, count + 1):
        mask = labels == index
        if mask[0, :].any() or mask[-1, :].any() or mask[:, 0].any() or mask[:, -1].any():
            continue
        w = value[mask]
        out.append((float((uu[mask] * w).sum() / w.sum()), float((vv[mask] * w).sum() / w.sum()), float(w.sum())))
    return np.array(out)


def test_jittered_microimages_sit_where_the_truth_says(args):
    # f/8 main lens behind f/4 microlenses: microimages of half the cell, apart from each other.
    path, work = render(args, "jittered", scene(8, "errors { position 0.005 seed 5 }"))
    meta = pt.metadata_of(path)
    errors = meta["microlens_array"]["errors"]
    assert errors["source"] == "drawn" and errors["position_sd_mm"] == 0.005 and errors["seed"] == 5
    rows = np.genfromtxt(os.path.join(work, "jittered.microimages.csv"), delimiter=",", names=True)
    assert "dx_mm" in rows.dtype.names and "tilt_deg" in rows.dtype.names
    assert meta["microimages"]["columns"][-6:] == ["dx_mm", "dy_mm", "dz_mm", "focal_length_mm", "tilt_deg",
                                                   "tilt_azimuth_deg"]
    rows = rows[np.isfinite(rows["u"])]
    truth = np.stack([rows["u"], rows["v"]], axis=1)
    projected = np.array([projected_centre_px(int(r["k"]), int(r["l"]), r["dx_mm"], r["dy_mm"]) for r in rows])
    lattice = np.array([projected_centre_px(int(r["k"]), int(r["l"]), 0.0, 0.0) for r in rows])
    # The truth is the projection of the displaced centre (a thin lens, d = f, no vignetting).
    assert np.abs(truth - projected).max() < 0.01, np.abs(truth - projected).max()
    moved = np.hypot(*(truth - lattice).T)
    print("true centres from the lattice: rms %.3f px, max %.3f px" % (math.sqrt((moved ** 2).mean()), moved.max()))
    assert math.sqrt((moved ** 2).mean()) > 0.2
    # The rendered microimages.
    found = component_centroids(pt.read_linear(path))
    assert len(found) >= 40, len(found)
    distances = []
    for u, v, _ in found:
        d = np.hypot(truth[:, 0] - u, truth[:, 1] - v)
        i = int(d.argmin())
        distances.append(d[i])
        assert d[i] < 0.05, "microimage at (%.2f, %.2f): truth (%.3f, %.3f) is %.3f px away" % (
            u, v, truth[i, 0], truth[i, 1], d[i])
    print("rendered centroids from the truth: mean %.4f px, max %.4f px over %d microimages"
          % (np.mean(distances), np.max(distances), len(found)))


def test_a_lens_table_made_of_the_truth_gives_the_same_render(args):
    errors = "errors { position 0.003 0.002 focal_length 0.02 rotation 2 seed 9 }"
    drawn, work = render(args, "drawn", scene(4, errors, "samples 16"))
    table = os.path.join(work, "drawn.microimages.csv")
    tabled, _ = render(args, "tabled", scene(4, 'lens_table "%s"' % table, "samples 16"))
    meta = pt.metadata_of(tabled)
    assert meta["microlens_array"]["errors"]["source"] == "lens_table"
    a, b = pt.read_linear(drawn), pt.read_linear(tabled)
    # The table holds the lenses whose microimages are in the picture; the lenses beyond it (ideal in
    # the tabled render) reach only the picture's edge, so compare 20 px inside it. The focal lengths
    # read back within a rounding (f from the CSV over the type's f), which may move a sample across
    # a rim: at most one sample of 16 in one pixel of 1000.
    d = np.abs(a - b).max(axis=2)[20:-20, 20:-20]
    print("tabled against drawn: %d of %d interior pixels differ, by at most %.4f" % ((d > 2e-3).sum(), d.size, d.max()))
    assert (d > 2e-3).sum() <= d.size // 1000
    assert d.max() < 1 / 16.0 + 2e-3
    ideal = pt.read_linear(render(args, "ideal", scene(4, "", "samples 16"))[0])
    assert np.abs(a - ideal).max() > 0.1, "the errors change the picture"


def central_mean(path):
    image = pt.read_linear(path)[..., :3]
    return float(image[H // 4: 3 * H // 4, W // 4: 3 * W // 4].mean())


def test_masked_array_delivers_the_fill_factors_share_of_the_light(args):
    ideal = central_mean(render(args, "full", scene(4, ""))[0])
    masked_path, _ = render(args, "masked", scene(4, "fill_factor 0.6 mask on"))
    masked = central_mean(masked_path)
    clear = central_mean(render(args, "clear", scene(4, "fill_factor 0.6"))[0])
    meta = pt.metadata_of(masked_path)["microlens_array"]
    assert meta["fill_factor"] == 0.6 and meta["gap"] == "masked" and meta["baffles"] is False
    print("white world, central half: ideal %.5f, masked %.5f (ratio %.4f), clear gaps %.5f (ratio %.4f)"
          % (ideal, masked, masked / ideal, clear, clear / ideal))
    assert abs(masked / ideal - 0.6) < 0.01
    assert abs(clear / ideal - 1.0) < 0.01


REFRACTING_ERRORS = "errors { position 0.002 focal_length 0.02 rotation 0.5 seed 3 }"
REFRACTING_SIZE = 150


def refracting_scene(error_anchors, errors=REFRACTING_ERRORS):
    """Plano-convex caps (R 0.09 mm, n 1.5) behind a thin f/3.5 lens, with all three kinds of errors."""
    return (pt.WORLD_HEADER + "background { rgb 1 }\n"
            "camera { plenoptic location <0, 0, 0> look_at <0, 0, 1>\n"
            "  main_lens { thin_lens focal_length 50 f_number 3.5 distance 50 }\n"
            "  microlens_array { hexagonal pitch 0.1\n"
            "    lens { surface { radius 0.09 } thickness 0.025 ior 1.5 substrate 0.05 curved_side scene }\n"
            "    distance 0.13 %s }\n"
            "  sensor { pixel_size %r } samples 1 microimage_centres on microimage_error_anchors %d\n}\n"
            % (errors, PIXEL, error_anchors))


_refracting_renders = {}


def refracting_render(args, name, error_anchors, errors=REFRACTING_ERRORS):
    """The render's image path (each scene rendered once for the tests that read it)."""
    if name not in _refracting_renders:
        work = os.path.join(args.work, "array_errors")
        _refracting_renders[name] = pt.render(args.povray, work, name, refracting_scene(error_anchors, errors),
                                              REFRACTING_SIZE, REFRACTING_SIZE)
    return _refracting_renders[name]


def truth_of(image_path):
    return np.genfromtxt(image_path[:-len(".png")] + ".microimages.csv", delimiter=",", names=True)


def test_refracting_lenses_with_errors_corrected_from_anchors_match_measuring_each(args):
    """`microimage_error_anchors N` (docs/camera.md): the render's truth takes each refracting lens as
    the ideal one corrected for its errors from Jacobian anchors N lenses apart; against measuring
    every lens (the default), lens by lens, within 0.02 px and 0.005 of lit fraction (the library's
    own test allows 0.03 px where neighbours cut lit parts of cells; seen here 0.006 px, 0.001)."""
    measured = refracting_render(args, "refracting_measured", 0)
    corrected = refracting_render(args, "refracting_corrected", 4)
    integration = pt.metadata_of(corrected)["microimages"]["integration"]
    assert "error_anchor_step" not in pt.metadata_of(measured)["microimages"]["integration"]
    assert integration["error_anchor_step"] == 4 and integration["error_anchors"] > 0, integration
    a, b = truth_of(measured), truth_of(corrected)
    assert len(a) == len(b) >= 150 and (a["k"] == b["k"]).all() and (a["l"] == b["l"]).all()
    assert integration["corrected_lenses"] >= len(b) // 2, integration
    lit = np.isfinite(a["u"])
    assert (lit == np.isfinite(b["u"])).all() and lit.sum() >= 150
    du = np.maximum(np.abs(a["u"] - b["u"]), np.abs(a["v"] - b["v"]))[lit]
    dlit = np.abs(a["lit_fraction"] - b["lit_fraction"])[lit]
    moved = np.hypot(a["residual_u"], a["residual_v"])[lit]
    print("corrected against measured, %d lenses: largest %.4f px, median %.4f px, lit fraction %.2g; "
          "the errors move centres off the lattice by up to %.3f px" % (lit.sum(), du.max(), np.median(du),
                                                                       dlit.max(), moved.max()))
    assert du.max() < 0.02 and dlit.max() < 0.005
    assert moved.max() > 0.3, "the errors move the microimages (else the comparison says little)"


def test_a_lens_table_of_refracting_lenses_gives_the_same_truth(args):
    """The truth of refracting caps with errors, given back as a lens_table: each row's
    focal_length_mm (the cap's paraxial focal length times its factor) reads back as the same
    focal length, and every lens whose neighbours are all in the table has the same microimage
    (the lenses beyond the table are ideal, so the table's border lenses may differ). Until
    2026-11-29 a refracting array's table divided by the thin lenses' focal length, which it does
    not have: every focal length became infinite and centres moved by up to 0.34 px."""
    drawn = refracting_render(args, "refracting_measured", 0)
    table = drawn[:-len(".png")] + ".microimages.csv"
    tabled = refracting_render(args, "refracting_tabled", 0, 'lens_table "%s"' % table)
    a, b = truth_of(drawn), truth_of(tabled)
    errors = pt.metadata_of(tabled)["microlens_array"]["errors"]
    assert errors["source"] == "lens_table" and errors["max_focal_deviation"] is not None, errors
    paraxial = 0.09 / (1.5 - 1)  # a plano-convex lens's focal length, R / (n - 1), whatever its thickness
    assert abs(errors["max_focal_deviation"] - np.abs(a["focal_length_mm"] / paraxial - 1).max()) < 1e-9
    assert (a["k"] == b["k"]).all() and (a["l"] == b["l"]).all()
    assert np.allclose(a["focal_length_mm"], b["focal_length_mm"], rtol=1e-12, atol=0)
    keys = set(zip(a["k"].astype(int), a["l"].astype(int)))
    around = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, 1), (1, -1), (-1, -1)]
    inside = np.array([all((k + dk, l + dl) in keys for dk, dl in around)
                       for k, l in zip(a["k"].astype(int), a["l"].astype(int))]) & np.isfinite(a["u"])
    assert inside.sum() >= 100
    du = np.maximum(np.abs(a["u"] - b["u"]), np.abs(a["v"] - b["v"]))[inside]
    print("tabled against drawn: %d lenses inside the table, largest %.2g px" % (inside.sum(), du.max()))
    assert du.max() < 1e-6
    assert np.abs(a["lit_fraction"] - b["lit_fraction"])[inside].max() < 1e-6


def check_one_row_table(args, name, focal, scene_with, refused_with):
    """Renders scene_with('lens_table "<table>"') with a table of one row, lens (0, 0) of focal
    length `focal`: refused, naming each of `refused_with` (when given), or rendered."""
    work = os.path.join(args.work, "array_errors")
    os.makedirs(work, exist_ok=True)
    table = os.path.join(work, "%s_%g.csv" % (name, focal))
    with open(table, "w") as f:
        f.write("k,l,focal_length_mm\n0,0,%r\n" % focal)
    status, output = pt.render(args.povray, work, "%s_%g" % (name, focal), scene_with('lens_table "%s"' % table),
                               40, 30, expect_failure=True)
    text = " ".join(output.split())
    if not refused_with:
        assert status == 0, text[-2000:]
        return
    assert status != 0, text[-2000:]
    # POV-Ray wraps its messages at 80 columns, inside long words (paths) too: compare without spaces.
    squashed = "".join(output.split())
    for fragment in refused_with:
        assert "".join(fragment.split()) in squashed, (fragment, text[-2000:])


def test_a_lens_table_that_shrinks_a_cap_below_its_cell_is_refused(args):
    """A refracting lens's radius scales with its focal length (R = f (n - 1)): a table row whose
    focal length leaves the cap narrower than its cell is refused, naming the file, the lens, its
    focal length and the cell (0.1 mm gives R = 0.05 mm; the hexagonal cell's corners are 0.1 / sqrt(3)
    = 0.0577 mm out). A row at 0.17 mm (R = 0.085 mm) is accepted."""
    def scene_with(table):
        return refracting_scene(0, table).replace("samples 1", "samples 1 microimage_centres off")
    check_one_row_table(args, "shrunk", 0.1, scene_with, ("lens_table", "shrunk_0.1.csv", "lens (0, 0)",
                                                          "focal_length_mm 0.1", "does not cover the lens's cell",
                                                          "0.0577"))
    check_one_row_table(args, "shrunk", 0.17, scene_with, ())


def test_a_lens_table_focal_length_far_from_its_types_is_refused(args):
    """Measured focal lengths must lie within 20 % of the lens type's (drawn errors reach 4 x 5 %):
    1.5 times the array's 0.6 mm is refused with the lens, the value and the ratio (a row of 1e-300
    once put a microimage centre at 1.7e298 px); 1.1 times renders."""
    def scene_with(table):
        return scene(4, table, "samples 1")
    check_one_row_table(args, "focal", 0.9, scene_with, ("lens_table", "lens (0, 0)", "focal_length_mm 0.9",
                                                         "1.5 times its type's 0.6 mm", "within 20 %"))
    check_one_row_table(args, "focal", 0.66, scene_with, ())
