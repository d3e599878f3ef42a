# SPDX-License-Identifier: AGPL-3.0-or-later
"""Microimage centres through a real main lens (`<image>.microimages.csv`) against the
independent reference tracer of the tests (plenoptic_testing.lens_tracer).

With pinhole microlenses a sensor point S receives light through lens (k, l) exactly when the ray
S -> the pinhole's centre passes the whole main lens. The reference counts that on a fine grid of
sensor points around each lens and takes the lit points' centroid and area: the camera's centres
must agree within 0.02 px, its lit fractions within 0.002 + 0.5 % (the reference grid's step
bounds its own accuracy on small cat's eyes). The corner microimages are cat's eyes
(the lens's clear apertures), whose centroids leave the paraxial lattice; the lattice fit and
the residuals in the files must be the least-squares fit of the listed centres.
"""
import json
import math
import os

import numpy as np

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt
from plenoptic_testing.real_lens_scenes import camera_scene, inline_prescription, reference_lens

W = H = 120
PIXEL = 0.5            # mm
PITCH, D_ARRAY = 2.5, 8.5


def render_with_pinholes(args, name):
    scene = camera_scene(inline_prescription() + " focus_distance 3",
                         "  microlens_array { rectangular pitch %r pinhole distance %r }\n"
                         "  sensor { pixel_size <%r, %r> } samples 1\n" % (PITCH, D_ARRAY, PIXEL, PIXEL))
    path = pt.render(args.povray, args.work, name, scene, W, H, timeout=300)
    meta = pt.metadata_of(path)
    rows = np.genfromtxt(os.path.join(args.work, name + ".microimages.csv"), delimiter=",", names=True)
    return meta, rows


def reference_microimage(lens, D, k, l, u0, v0, half=5.0, step=0.04):
    """Centroid (u, v) and area (px^2) of the sensor points around (u0, v0) whose ray through
    pinhole (k, l) passes the lens; None when none does."""
    offsets = (np.arange(int(round(2 * half / step))) + 0.5) * step - half
    uu, vv = np.meshgrid(u0 + offsets, v0 + offsets)
    u, v = uu.ravel(), vv.ravel()
    # Pixel (centre convention) -> sensor (optics frame; the lens frame's z is L + D + d).
    x = -(u + 0.5 - W / 2.0) * PIXEL
    y = (v + 0.5 - H / 2.0) * PIXEL
    origins = np.stack([x, y, np.full(len(x), lens.length + D + D_ARRAY)], axis=1)
    towards = np.stack([k * PITCH - x, l * PITCH - y, np.full(len(x), -D_ARRAY)], axis=1)
    passed = lt.trace_image_to_object(lens, origins, towards).passed
    if not passed.any():
        return None
    return float(u[passed].mean()), float(v[passed].mean()), float(passed.sum() * step * step)


def test_centres_and_lit_fractions_match_reference(args):
    meta, rows = render_with_pinholes(args, "microimages_pinholes")
    info = meta["microimages"]
    assert info["file"] == "microimages_pinholes.microimages.csv"
    assert info["lenses"] == len(rows)
    D = meta["main_lens"]["distance_mm"]
    lens = reference_lens()
    par = lt.paraxial_data(lens)
    # The microimage cell: the lens cell projected from the exit pupil's centre onto the sensor.
    pupil_z = lens.length - par.exit_pupil_z      # optics frame, from the rear vertex
    cell_px = (PITCH * (pupil_z + D + D_ARRAY) / (pupil_z + D)) ** 2 / PIXEL ** 2

    # Every lattice centre in the picture is listed once.
    lattice = meta["microimage_lattice"]
    origin, (a, b) = np.array(lattice["origin_px"]), np.array(lattice["basis_px"])
    listed = {(int(r["k"]), int(r["l"])) for r in rows}
    expected = set()
    for l in range(-40, 41):
        for k in range(-40, 41):
            c = origin + k * a + l * b
            if -0.5 <= c[0] < W - 0.5 and -0.5 <= c[1] < H - 0.5:
                expected.add((k, l))
    assert listed == expected

    # The reference on the rows and columns through the centre and along both diagonals.
    errors, fraction_errors, worst_shift, cats_eyes = [], [], 0.0, 0
    for r in rows:
        k, l = int(r["k"]), int(r["l"])
        if not (k == 0 or l == 0 or abs(k) == abs(l)):
            continue
        lattice_centre = origin + k * a + l * b
        ref = reference_microimage(lens, D, k, l, *lattice_centre)
        if ref is None:
            assert np.isnan(r["u"]) and r["lit_fraction"] == 0, (k, l)
            continue
        u, v, area = ref
        errors.append(math.hypot(r["u"] - u, r["v"] - v))
        # The reference's grid knows a boundary to its step: about perimeter * step / 2 of area.
        fraction_errors.append(abs(r["lit_fraction"] - area / cell_px) / (0.002 + 0.005 * area / cell_px))
        worst_shift = max(worst_shift, math.hypot(u - lattice_centre[0], v - lattice_centre[1]))
        cats_eyes += area / cell_px < 0.7 * rows["lit_fraction"].max()
    print("centres against the reference: max %.4f px over %d lenses; lit fractions: max %.2f of the tolerance; "
          "largest shift from the paraxial lattice %.3f px; %d cat's eyes"
          % (max(errors), len(errors), max(fraction_errors), worst_shift, cats_eyes))
    assert len(errors) >= 60
    assert max(errors) <= 0.02, max(errors)
    assert max(fraction_errors) <= 1.0, max(fraction_errors)
    # The test means something: the corners are cat's eyes, moved off the lattice by more than
    # the tolerance many times over.
    assert cats_eyes >= 4 and worst_shift > 0.2, (cats_eyes, worst_shift)


def test_lattice_fit_is_the_least_squares_fit_of_the_centres(args):
    meta, rows = render_with_pinholes(args, "microimages_fit")
    fit = meta["microimages"]["lattice_fit"]
    lit = ~np.isnan(rows["u"])
    k, l = rows["k"][lit], rows["l"][lit]          # rectangular: skew = row form
    design = np.stack([np.ones_like(k), k, l], axis=1)
    solution, *_ = np.linalg.lstsq(design, np.stack([rows["u"][lit], rows["v"][lit]], axis=1), rcond=None)
    assert np.allclose(solution[0], fit["origin_px"], atol=1e-7)
    assert np.allclose(solution[1], fit["basis_px"][0], atol=1e-9)
    assert np.allclose(solution[2], fit["basis_px"][1], atol=1e-9)
    residual = np.stack([rows["u"][lit], rows["v"][lit]], axis=1) - design @ solution
    assert np.allclose(residual[:, 0], rows["residual_u"][lit], atol=1e-7)
    assert np.allclose(residual[:, 1], rows["residual_v"][lit], atol=1e-7)
    norms = np.hypot(residual[:, 0], residual[:, 1])
    assert math.isclose(fit["rms_residual_px"], float(np.sqrt((norms ** 2).mean())), rel_tol=1e-6)
    assert math.isclose(fit["max_residual_px"], float(norms.max()), rel_tol=1e-6)
    assert fit["lenses"] == int(lit.sum()) == meta["microimages"]["lit_lenses"]
    worst = int(np.argmax(norms))
    assert fit["max_residual_lens"] == [int(k[worst]), int(l[worst])]
    # A real lens: the centres are off any lattice by more than the integration's error.
    assert fit["max_residual_px"] > 0.05


def test_no_file_without_an_array(args):
    scene = camera_scene(inline_prescription() + " focus_distance 3",
                         "  sensor { pixel_size <%r, %r> } samples 1\n" % (PIXEL, PIXEL))
    path = pt.render(args.povray, args.work, "microimages_no_array", scene, 40, 30, timeout=120)
    assert pt.metadata_of(path)["microimages"] is None
    assert not os.path.exists(os.path.join(args.work, "microimages_no_array.microimages.csv"))


def test_written_by_default_only_off_the_lattice(args):
    """By default behind a traced lens (and a distorted thin lens); on request behind an ideal one;
    `microimage_centres off` skips it."""
    array = "  microlens_array { rectangular pitch %r pinhole distance %r }\n" % (PITCH, D_ARRAY)
    sensor = "  sensor { pixel_size <%r, %r> } samples 1\n" % (PIXEL, PIXEL)
    cases = [
        ("mi_thin_default", "thin_lens focal_length 50 f_number 4 focus_distance 3", "", False),
        ("mi_thin_asked", "thin_lens focal_length 50 f_number 4 focus_distance 3", "  microimage_centres\n", True),
        ("mi_thin_distorted", "thin_lens focal_length 50 f_number 4 focus_distance 3 "
                              "distortion { radial <-0.05, 0, 0> }", "", True),
        ("mi_real_off", inline_prescription() + " focus_distance 3", "  microimage_centres off\n", False),
    ]
    for name, main, extra, written in cases:
        path = pt.render(args.povray, args.work, name, camera_scene(main, array + sensor + extra), 40, 30,
                         timeout=120)
        csv = os.path.join(args.work, name + ".microimages.csv")
        meta = pt.metadata_of(path)
        assert os.path.exists(csv) == written, name
        assert (meta["microimages"] is not None) == written, name
        if written and name == "mi_thin_asked":
            rows = np.genfromtxt(csv, delimiter=",", names=True)
            # An ideal lens: the centres are the metadata's lattice.
            lattice = meta["microimage_lattice"]
            origin, (a, b) = np.array(lattice["origin_px"]), np.array(lattice["basis_px"])
            for r in rows:
                c = origin + r["k"] * a + r["l"] * b
                assert math.hypot(r["u"] - c[0], r["v"] - c[1]) < 1e-3, (r, c)
