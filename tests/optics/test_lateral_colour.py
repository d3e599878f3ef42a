# SPDX-License-Identifier: AGPL-3.0-or-later
"""Lateral colour of the 22 mm wide angle (lenses/wide_angle_22mm_laikin_f3.5.dat) with its
glasses' Abbe numbers, rendered with `spectral 8` per channel, against the tests' own reference
tracer (plenoptic_testing.lens_tracer) at the same wavelengths.

The lens file names its Schott glasses; the test writes the file again with a fifth column, V_d,
the catalogue's figures (SCHOTT optical glass catalogue, as printed in SCHOTT.xls, read from the
data of PyPI's `opticalglass` 1.1.1: N-PK51 76.98, SF1 29.51, LF5 40.85, N-LAK21 60.10; their n_d
there are the file's). The catalogue's lens file itself stays without them, so that its renders,
metadata and golden images do not change.

- Point images per channel: a small sphere at three field heights (about 9, 18 and 25 degrees),
  each rendered without an array on a small sensor of 2 um pixels moved (sensor offset) to where
  the point images, f/8, `spectral 8`. A channel's picture is the sum over the bands of the band's
  picture times the channel's weight (the metadata's spectral.weights), so its centroid is the mean
  of the bands' spot centroids weighted by weight x the band's flux; the reference traces each band's
  spot (irradiance centroid over the entrance side, lens_tracer.spot_centroid_no_array) through the
  lens at the band's two-term indices. Each channel's rendered centroid within 0.2 px of it.
- The lateral colour itself: the R - B centroid separation is 1.4 to 3.3 px here (the reference's,
  red farther from the axis);
  the rendered one must have its sign and agree within 0.2 px, so a render that ignored dispersion
  (R = B) fails.
- plenoptic-project --wavelength (the same metadata): each point at the channels' wavelengths
  against the reference's spot centroid at that single wavelength (0.05 px); a wavelength outside
  380-720 nm is refused.
- The metadata's distortion profile per channel (main_lens.distortion_profile.channels) against
  the reference's chief rays through the stop's centre at the channel wavelengths (1e-6 mm), the
  same object points as the d line's profile.
"""
import math
import os
import re
import subprocess

import numpy as np
import pytest

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt
from plenoptic_testing.real_lens_scenes import camera_scene

LENSES_DIR = os.path.join(os.path.dirname(__file__), "..", "..", "lenses")
WIDE_ANGLE = "wide_angle_22mm_laikin_f3.5.dat"
# V_d from the SCHOTT catalogue (see the module docstring).
ABBE = {"N-PK51": 76.98, "SF1": 29.51, "LF5": 40.85, "N-LAK21": 60.10}

PIXEL = 0.002       # mm
SIZE = 40           # pixels a side
DISTANCE_M = 3.0    # the points' plane, in front of the front vertex
HEIGHTS_M = (0.5, 1.0, 1.4)
SPHERE_M = 0.0005   # radius: about 1.8 px in the image
F_NUMBER = 8.0


def lens_text_with_abbe():
    """The catalogue file with each glass row's V_d appended, by the glass its comment names."""
    with open(os.path.join(LENSES_DIR, WIDE_ANGLE)) as f:
        lines = f.read().splitlines()
    out, glasses = [], 0
    for line in lines:
        match = re.match(r"^(\s*[-0-9.]+\s+[-0-9.]+\s+[-0-9.]+\s+[-0-9.]+)(\s*#\s*\d+\s+(\S+).*)$", line)
        if match:
            abbe = ABBE.get(match.group(3), 0.0)
            glasses += abbe > 0
            line = "%s %6.2f%s" % (match.group(1), abbe, match.group(2))
        out.append(line)
    assert glasses == 5, glasses  # N-PK51, SF1, LF5, SF1, N-LAK21
    return "\n".join(out) + "\n"


@pytest.fixture(scope="module")
def setup(args):
    text = lens_text_with_abbe()
    surfaces = lt.parse_lens_file(text)
    lens = lt.Lens(surfaces)
    par = lt.paraxial_data(lens)
    D = lt.paraxial_image_distance(lens, DISTANCE_M * 1000.0)
    stop = par.efl / F_NUMBER / (par.entrance_pupil_diameter / lens.stop_diameter)
    work = os.path.join(args.work, "lateral_colour")
    os.makedirs(work, exist_ok=True)
    pt.write_text(os.path.join(work, "wide_glass.dat"), text)
    return dict(surfaces=surfaces, lens=lens, D=D, stop=stop, work=work)


def optics_point(lens, height_m):
    # location <0, 0, -3>, looking along +z: the world point (0, h, 0) in the optics frame.
    return lt.world_to_optics(np.array([0.0, height_m, 0.0]), np.array([0, 0, -DISTANCE_M]), np.array([1.0, 0, 0]),
                              np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), 1000.0, lens)


def spot_at(setup, height_m, wavelength_nm):
    at = lt.Lens(lt.surfaces_at_wavelength(setup["surfaces"], wavelength_nm), stop_diameter=setup["stop"])
    return lt.spot_centroid_no_array(at, optics_point(setup["lens"], height_m), setup["D"], 400000)


def render_point(args, setup, index, height_m):
    offset_y = spot_at(setup, height_m, lt_d_line()).y
    sphere = "sphere { <0, %r, 0>, %r pigment { rgb 1 } finish { ambient 1 diffuse 0 } }\n" % (height_m, SPHERE_M)
    scene = camera_scene('lens_file "wide_glass.dat" f_number %r distance %r' % (F_NUMBER, setup["D"]),
                         "  sensor { pixel_size %r offset <0, %r> } samples 256 spectral 8\n" % (PIXEL, offset_y),
                         background="rgb 0", objects=sphere)
    path = pt.render(args.povray, setup["work"], "point%d" % index, scene, SIZE, SIZE,
                     extra=("+L%s" % setup["work"],), timeout=600)
    return path, offset_y


def lt_d_line():
    return 587.5618


def channel_centroids(image):
    """(u, v) centroid of each channel over the whole (black elsewhere) picture."""
    rows, cols = np.mgrid[0:image.shape[0], 0:image.shape[1]]
    out = []
    for c in range(3):
        channel = image[..., c]
        assert channel.sum() > 0
        out.append(((channel * cols).sum() / channel.sum(), (channel * rows).sum() / channel.sum()))
    return out


@pytest.fixture(scope="module")
def renders(args, setup):
    return [render_point(args, setup, i, h) for i, h in enumerate(HEIGHTS_M)]


def test_channel_centroids_match_reference(setup, renders):
    separations = []
    for (path, offset_y), height in zip(renders, HEIGHTS_M):
        meta = pt.read_json(path[:-len(".png")] + ".plenoptic.json")
        spectral = meta["spectral"]
        bands = spectral["wavelengths_nm"]
        spots = [spot_at(setup, height, nm) for nm in bands]
        expected = []
        for name in ("r", "g", "b"):
            weights = np.array(spectral["weights"][name]) * np.array([s.count for s in spots])
            y = float(np.dot(weights, [s.y for s in spots]) / weights.sum())
            x = float(np.dot(weights, [s.x for s in spots]) / weights.sum())
            expected.append(pt.sensor_to_pixel(x, y, SIZE, SIZE, PIXEL, PIXEL, 0.0, offset_y))
        image = pt.read_linear(path)
        measured = channel_centroids(image)
        errors = [math.hypot(m[0] - e[0], m[1] - e[1]) for m, e in zip(measured, expected)]
        print("height %.1f m: rendered (u, v) R %s G %s B %s; reference R %s G %s B %s; errors %s px" %
              (height, measured[0], measured[1], measured[2], expected[0], expected[1], expected[2], errors))
        assert max(errors) <= 0.2, errors
        predicted = expected[0][1] - expected[2][1]
        rendered = measured[0][1] - measured[2][1]
        separations.append((predicted, rendered))
        # The lateral colour: red images farther from the axis than blue. The image of a point
        # above the axis lies below it on the sensor (y < 0), and v follows the sensor's y
        # (pt.sensor_to_pixel), so red's v is the smaller, by more than a pixel here.
        assert predicted < -1.0, predicted
        assert rendered < 0 and abs(rendered - predicted) <= 0.2, (rendered, predicted)
    print("R - B along v (predicted, rendered) px:", separations)


def run_project(args, metadata, wavelength, points):
    cmd = [args.project] + (["--wavelength", str(wavelength)] if wavelength is not None else []) + [metadata]
    cmd += ["%.17g" % c for p in points for c in p]
    return subprocess.run(cmd, capture_output=True, text=True)


def test_project_at_wavelength_matches_reference(args, setup, renders):
    for (path, offset_y), height in zip(renders, HEIGHTS_M):
        metadata = path[:-len(".png")] + ".plenoptic.json"
        meta = pt.read_json(metadata)
        shifts = []
        for nm in meta["spectral"]["channel_wavelengths_nm"]:
            run = run_project(args, metadata, nm, [(0.0, height, 0.0)])
            assert run.returncode == 0, run.stderr
            fields = run.stdout.split()
            u, v = float(fields[3]), float(fields[4])
            spot = spot_at(setup, height, nm)
            eu, ev = pt.sensor_to_pixel(spot.x, spot.y, SIZE, SIZE, PIXEL, PIXEL, 0.0, offset_y)
            assert math.hypot(u - eu, v - ev) <= 0.05, (nm, u, v, eu, ev)
            shifts.append(v)
        assert shifts[0] - shifts[2] < -1.0, shifts  # red farther from the axis by more than a pixel
        # Without --wavelength: the d line, as before.
        run = run_project(args, metadata, None, [(0.0, height, 0.0)])
        spot = spot_at(setup, height, lt_d_line())
        eu, ev = pt.sensor_to_pixel(spot.x, spot.y, SIZE, SIZE, PIXEL, PIXEL, 0.0, offset_y)
        fields = run.stdout.split()
        assert math.hypot(float(fields[3]) - eu, float(fields[4]) - ev) <= 0.05
    for bad in ("379", "721", "nan", "blue"):
        run = run_project(args, metadata, bad, [(0.0, 0.5, 0.0)])
        assert run.returncode == 2 and "--wavelength" in run.stderr, (bad, run.stderr)
        assert "380 to 720 nm" in run.stderr or "number of nanometres" in run.stderr, run.stderr


def test_distortion_profile_per_channel_matches_reference(setup, renders):
    import importlib.util
    spec = importlib.util.spec_from_file_location(
        "test_distortion_profile", os.path.join(os.path.dirname(__file__), "test_distortion_profile.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    reference_chief_height = module.reference_chief_height
    meta = pt.read_json(renders[2][0][:-len(".png")] + ".plenoptic.json")
    profile = meta["main_lens"]["distortion_profile"]
    channels = profile["channels"]
    assert channels["wavelengths_nm"] == meta["spectral"]["channel_wavelengths_nm"]
    lens = setup["lens"]
    par = lt.paraxial_data(lens)  # the d line's: the profile's object points are the d line's
    L, D = lens.length, meta["main_lens"]["distance_mm"]
    x_image = (L + D) - par.rear_focal_z
    object_z = par.front_focal_z - par.efl ** 2 / x_image
    magnification = x_image / par.efl
    d_rows = profile["samples"]
    real = []
    worst = 0.0
    for c, name in enumerate(("r", "g", "b")):
        at = lt.Lens(lt.surfaces_at_wavelength(setup["surfaces"], channels["wavelengths_nm"][c]))
        rows = channels[name]
        assert len(rows) == len(d_rows) == 17
        for row, d_row in zip(rows, d_rows):
            assert row[0] == d_row[0] and row[2] == d_row[2]  # the same object points
            height, angle = reference_chief_height(at, (0.0, row[2] / magnification, object_z), L + D)
            worst = max(worst, abs(-height - row[3]))
            assert abs(-height - row[3]) <= 1e-6, (name, row, -height)
        real.append([row[3] for row in rows])
    print("channel profiles: heights within %.2e mm; R - B at the largest height %.5f mm" % (worst, real[0][-1] - real[2][-1]))
    # Lateral colour: off the axis red's chief ray lands farther out than blue's (by microns).
    assert all(r - b > 1e-4 for r, b in zip(real[0][2:], real[2][2:])), (real[0], real[2])


def test_microimage_centres_per_channel(args, setup):
    """With an array and `spectral`, <image>.microimages.csv gains u_r .. v_b, the metadata names
    them, the package's reader reads both forms, and through the dispersing wide angle the red
    and blue centres move apart off the axis, while a render without `spectral` writes the file as
    before."""
    from plenoptic_lf import microimages as mi
    from plenoptic_lf.metadata import load_metadata
    array = "microlens_array { hexagonal pitch 0.3 focal_length 1.2 distance 1.2 }\n"
    names = {}
    for name, extra in (("centres_spectral", " spectral 4"), ("centres_plain", "")):
        scene = camera_scene('lens_file "wide_glass.dat" f_number 4 focus_distance 3',
                             array + "  sensor { pixel_size 0.05 } samples 1%s\n" % extra)
        names[name] = pt.render(args.povray, setup["work"], name, scene, 160, 120, extra=("+L%s" % setup["work"],))
    stem = os.path.join(setup["work"], "centres_spectral")
    meta = pt.read_json(stem + ".plenoptic.json")
    assert meta["microimages"]["columns"][7:] == ["u_r", "v_r", "u_g", "v_g", "u_b", "v_b"]
    with open(stem + ".microimages.csv") as f:
        assert f.readline().strip() == "k,l,u,v,lit_fraction,residual_u,residual_v,u_r,v_r,u_g,v_g,u_b,v_b"
    plain = pt.read_json(os.path.join(setup["work"], "centres_plain.plenoptic.json"))
    assert plain["microimages"]["columns"] == ["k", "l", "u", "v", "lit_fraction", "residual_u", "residual_v"]
    with open(os.path.join(setup["work"], "centres_plain.microimages.csv")) as f:
        assert f.readline().strip() == "k,l,u,v,lit_fraction,residual_u,residual_v"

    package_meta = load_metadata(stem + ".plenoptic.json")
    centres = mi.MeasuredCentres(package_meta, stem + ".microimages.csv")
    assert centres.has_channels
    plain_centres = mi.MeasuredCentres(load_metadata(os.path.join(setup["work"], "centres_plain.plenoptic.json")),
                                       os.path.join(setup["work"], "centres_plain.microimages.csv"))
    assert not plain_centres.has_channels
    lit = centres.status == mi.LIT
    ll, kk = np.nonzero(lit)
    k, l = (kk + centres.k_min).astype(float), (ll + centres.l_min).astype(float)
    u, v, _ = centres.centre(k, l)
    # Without channels the reader gives the d line's centre for every channel.
    pu, pv, _ = plain_centres.channel_centre(0, k, l)
    qu, qv, _ = plain_centres.centre(k, l)
    assert np.array_equal(pu, qu) and np.array_equal(pv, qv)
    ur, vr, _ = centres.channel_centre(0, k, l)
    ub, vb, _ = centres.channel_centre(2, k, l)
    assert np.all(np.isfinite(ur)) and np.all(np.isfinite(ub))
    # The channels' centres differ where the field is large, all one way (the exit pupil's image
    # moves with the glass behind the stop); about a thousandth of a pixel at these 50 um pixels,
    # systematic and above the integration's error (its size is checked against the lens written
    # at each channel's index by the unit test MicroimageTruth.CentresPerChannel...).
    cx, cy = meta["principal_point_px"]
    radius = np.hypot(u - cx, v - cy)
    outer = radius > 0.6 * radius.max()
    radial = ((ur - ub) * (u - cx) + (vr - vb) * (v - cy)) / np.maximum(radius, 1e-9)
    print("red - blue centre, radially, outer lenses: mean %.4f px, range %.4f .. %.4f px (%d lenses)"
          % (radial[outer].mean(), radial[outer].min(), radial[outer].max(), outer.sum()))
    assert np.all(radial[outer] < 0) or np.all(radial[outer] > 0), radial[outer]
    assert np.abs(radial[outer]).mean() > 5e-4, radial[outer]
