# SPDX-License-Identifier: AGPL-3.0-or-later
"""Renders through a prescription main lens against the independent reference tracer
of the tests (plenoptic_testing.lens_tracer: exact tracing and paraxial data written apart from
the camera's code).

- Paraxial data: the metadata's effective focal length, back focus, principal planes, pupils,
  f-number and the gap D of a focused lens equal the reference's y-u trace.
- White image with pinhole microlenses: every sensor point has one ray through each pinhole, so
  a pixel's value in a white scene is the fraction of its area whose ray passes the whole lens
  (summed over the lenses that pass it): the reference computes it on an 8 x 8 grid per pixel,
  the camera with its own low-discrepancy samples. Off axis the clear apertures clip the
  microimages into cat's eyes; the two images must agree pixel by pixel within the sampling
  error of the two estimates.
- Point images without an array: small bright spheres on a grid over the field, in focus; the
  centroid of each rendered blob against the reference's irradiance centroid of the point's
  spot (rays over the whole entrance side, kept where they pass): 0.2 px.
"""
import math
import os

import numpy as np
import pytest
from scipy import ndimage

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt
from plenoptic_testing.real_lens_scenes import LENS_FILE_TEXT, camera_scene, inline_prescription, reference_lens

def test_paraxial_data_in_metadata(args):
    """Metadata of a focused lens_file lens against the reference's paraxial trace."""
    pt.write_text(os.path.join(args.work, "test_lens.dat"), LENS_FILE_TEXT)
    scene = camera_scene('lens_file "test_lens.dat" focus_distance 3',
                         "  sensor { pixel_size <0.05, 0.05> } samples 1\n")
    path = pt.render(args.povray, args.work, "real_lens_paraxial", scene, 16, 12, extra=("+L%s" % args.work,))
    meta = pt.metadata_of(path)
    main = meta["main_lens"]
    ref = lt.paraxial_data(reference_lens())
    length = reference_lens().length
    par = main["paraxial"]
    assert main["type"] == "prescription"
    assert main["prescription"]["lens_file"] == "test_lens.dat"
    close = lambda a, b: abs(a - b) <= 1e-9 * max(1.0, abs(b))
    checks = [
        ("effective_focal_length_mm", ref.efl), ("back_focal_distance_mm", ref.bfd),
        ("front_focal_distance_mm", ref.ffd), ("length_mm", length),
        # optics frame: z from the rear vertex towards the scene
        ("front_principal_plane_z_mm", length - ref.front_principal_z),
        ("rear_principal_plane_z_mm", length - ref.rear_principal_z),
        ("entrance_pupil_z_mm", length - ref.entrance_pupil_z),
        ("entrance_pupil_diameter_mm", ref.entrance_pupil_diameter),
        ("exit_pupil_z_mm", length - ref.exit_pupil_z),
        ("exit_pupil_diameter_mm", ref.exit_pupil_diameter), ("f_number", ref.f_number),
    ]
    wrong = [(key, par[key], want) for key, want in checks if not close(par[key], want)]
    assert not wrong, wrong
    assert close(main["focal_length_mm"], ref.efl) and close(main["f_number"], ref.f_number)
    # focus_distance 3 m from the front vertex: D is the paraxial image distance behind the rear vertex.
    assert close(main["distance_mm"], lt.paraxial_image_distance(reference_lens(), 3000.0))
    # The optics frame's origin is the rear vertex, the lens's length behind the scene's location.
    assert meta["camera_frame"]["location"] == pytest.approx([0, 0, -3 - length / 1000.0], abs=1e-12)


def test_white_image_pinhole_array_matches_reference(args):
    """Cat's-eye microimages through the full-aperture lens, pixel by pixel."""
    W = H = 120
    pixel = 0.5            # mm: a 60 mm square sensor, so the field reaches the vignetted zone
    pitch, d = 2.5, 8.5    # mm: 5 px microimages; d / p = 3.4, above the lens's working f-number (2.9)
    samples = 64
    scene = camera_scene(inline_prescription() + " focus_distance 3",
                         "  microlens_array { rectangular pitch %r pinhole distance %r }\n"
                         "  sensor { pixel_size <%r, %r> } samples %d\n" % (pitch, d, pixel, pixel, samples))
    path = pt.render(args.povray, args.work, "real_lens_white", scene, W, H, timeout=300)
    rendered = pt.read_linear(path)[..., :3].mean(axis=2)
    meta = pt.metadata_of(path)
    D = meta["main_lens"]["distance_mm"]
    assert D == pytest.approx(lt.paraxial_image_distance(reference_lens(), 3000.0), rel=1e-12)
    expected = lt.white_image_pinhole_array(reference_lens(), D, d, pitch, W, H, pixel, pixel, 8)
    pt.save_png(os.path.join(args.work, "real_lens_white_expected.png"), expected)

    # The cat's eyes are there: corner microimages are clipped, so less of the corner is lit.
    centre_lit = expected[H // 2 - 15:H // 2 + 15, W // 2 - 15:W // 2 + 15].mean()
    corner_lit = expected[:20, :20].mean()
    assert corner_lit < 0.8 * centre_lit, (corner_lit, centre_lit)

    diff = np.abs(rendered - expected)
    # Two estimates of a pixel's lit fraction: 64 camera samples (plus its 256 vignetting probes)
    # against the reference's 64-point grid. They differ only at microimage rims, by a few
    # samples' worth (seen: at most 0.047, 99th percentile 0.031); a wrong gap, pupil or clear
    # aperture moves whole rims, by up to 1.
    assert diff.max() <= 0.1, diff.max()
    assert np.percentile(diff, 99) <= 0.05, np.percentile(diff, 99)
    assert abs(rendered.mean() - expected.mean()) <= 0.002, (rendered.mean(), expected.mean())


@pytest.mark.parametrize("blades", [0, 7])
def test_white_image_without_array_matches_reference(args, blades):
    """Mechanical vignetting on a bare sensor: the relative lit area of the exit pupil's plane.

    A white scene through the lens at full aperture onto an 80 x 60 mm sensor, whose corners lie
    past the edge of the field: each pixel records the area through which its light passes the
    lens over the paraxial exit pupil's (1 on axis, falling where the front and rear elements
    cut the bundle). The reference counts that area on a 160 x 160 grid for the pixel centres
    along the middle row and the diagonal. With a round stop the camera looks the area up in its
    lit-area table; with a 7-blade iris it measures it per pixel with vignetting probes."""
    W, H = 160, 120
    pixel = 0.5
    iris = " blades 7" if blades else ""
    scene = camera_scene(inline_prescription() + iris + " focus_distance 3",
                         "  sensor { pixel_size <%r, %r> } samples 16\n" % (pixel, pixel))
    name = "real_lens_white_bare_%d" % blades
    path = pt.render(args.povray, args.work, name, scene, W, H, ext="exr", timeout=300)
    rendered = pt.read_linear(path)[..., :3].mean(axis=2)
    pt.save_png(os.path.join(args.work, name + "_view.png"), np.clip(rendered, 0, 1))
    D = pt.metadata_of(path)["main_lens"]["distance_mm"]
    lens = lt.Lens(lt.parse_lens_file(LENS_FILE_TEXT), iris_blades=blades)
    pixels = [(i, H // 2) for i in range(W // 2, W)] + [(W // 2 + k, H // 2 + k) for k in range(H // 2)]
    centres = [(-((i + 0.5) - W / 2.0) * pixel, ((j + 0.5) - H / 2.0) * pixel) for i, j in pixels]
    expected = lt.relative_lit_area_no_array(lens, D, centres, 160)
    got = np.array([rendered[j, i] for i, j in pixels])
    # The field is covered: on axis the whole pupil, vignetted towards the edge, dark in the corner.
    # (A regular 7-gon inscribed in the stop passes 7 sin(2 pi / 7) / (2 pi) = 87.1 % of it.)
    assert expected[0] > (0.95 if blades == 0 else 0.85) and expected.min() == 0.0 and ((expected > 0.05) & (expected < 0.9)).sum() >= 20
    diff = np.abs(got - expected)
    print("blades %d: lit area, render - reference: max %.4f, mean %.4f" % (blades, diff.max(), diff.mean()))
    if blades == 0:
        # The table (2 x 987 points a radius, 257 radii), the reference's grid (about 0.3 % each)
        # and the pixel's area (64 look-ups) against its centre: seen at most 0.0074.
        assert diff.max() <= 0.015, diff.max()
    else:
        # 16 samples and 48 probes a pixel: their sampling error in the vignetted zone (seen at
        # most 0.070, mean 0.018). A misplaced or mis-turned iris moves whole zones.
        assert diff.max() <= 0.1, diff.max()
        assert diff.mean() <= 0.025, diff.mean()
    assert np.all(np.isfinite(rendered))


def test_point_images_without_array_match_reference(args):
    """Small bright spheres over the field, in focus on a bare sensor: blob centroids."""
    W, H = 160, 120
    pixel = 0.2  # mm: a 32 x 24 mm sensor, half-field about 20 degrees
    distance_m = 3.0
    lens = reference_lens()
    length = lens.length
    D = lt.paraxial_image_distance(lens, distance_m * 1000.0)
    # Points on the plane 3 m in front of the front vertex, a 5 x 4 grid over 80 % of the field,
    # placed with the reference's paraxial magnification (principal plane to image over principal
    # plane to object).
    par = lt.paraxial_data(lens)
    magnification = (D + length - par.rear_principal_z) / (distance_m * 1000.0 + par.front_principal_z)
    half_w = 0.8 * 0.5 * W * pixel / magnification / 1000.0
    half_h = 0.8 * 0.5 * H * pixel / magnification / 1000.0
    points = [(x, y) for x in np.linspace(-half_w, half_w, 5) for y in np.linspace(-half_h, half_h, 4)]
    spheres = "".join("sphere { <%r, %r, 0>, 0.01 pigment { rgb 1 } finish { ambient 1 diffuse 0 } }\n" % p
                      for p in points)
    scene = camera_scene(inline_prescription() + " f_number 8 distance %r" % D,
                         "  sensor { pixel_size <%r, %r> } samples 400\n" % (pixel, pixel),
                         background="rgb 0", objects=spheres)
    path = pt.render(args.povray, args.work, "real_lens_points", scene, W, H, timeout=300)
    image = pt.read_linear(path)[..., :3].mean(axis=2)
    centroids = blob_centroids(image, len(points))  # (v, u)

    # f_number 8: the stop scaled so that the entrance pupil is EFL / 8 (the pupil scales with it).
    stopped = lt.Lens(lt.parse_lens_file(LENS_FILE_TEXT), stop_diameter=par.efl / 8 / (par.entrance_pupil_diameter / 10.0))
    errors, references = [], []
    for x, y in points:
        # The scene point in the optics frame: location <0,0,-3>, looking along +z.
        optics = lt.world_to_optics(np.array([x, y, 0.0]), np.array([0, 0, -3.0]), np.array([1.0, 0, 0]),
                                    np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), 1000.0, lens)
        spot = lt.spot_centroid_no_array(stopped, optics, D, 40000)
        u, v = lt.sensor_to_pixel(spot.x, spot.y, W, H, pixel, pixel)
        nearest = min(centroids, key=lambda c: math.hypot(c[1] - u, c[0] - v))
        errors.append(math.hypot(nearest[1] - u, nearest[0] - v))
        references.append((u, v))
    assert max(errors) <= 0.2, errors

    # Forward projection through the traced lens (plenoptic-project): the centroid of each point's
    # spot, against the reference's (the same quantity; both sample the light, so a few
    # hundredths of a pixel) and against the render.
    hits = pt.run_project(args.project, os.path.join(args.work, "real_lens_points.plenoptic.json"),
                          [(x, y, 0.0) for x, y in points])
    assert sorted(h[0] for h in hits) == list(range(len(points))), hits
    to_reference = [math.hypot(u - references[i][0], v - references[i][1]) for i, _, _, u, v in hits]
    print("plenoptic-project - reference spot centroid: max %.4f px" % max(to_reference))
    assert max(to_reference) <= 0.03, to_reference
    to_render = [min(math.hypot(c[1] - u, c[0] - v) for c in centroids) for _, _, _, u, v in hits]
    assert max(to_render) <= 0.2, to_render


def blob_centroids(image, expected_count):
    """Intensity centroids (v, u) of the bright blobs of a black image, each over a window around
    the blob (faint tails included)."""
    labels, count = ndimage.label(image > 0.01)
    assert count == expected_count, count
    centroids = []
    for row, col in ndimage.center_of_mass(image, labels, range(1, count + 1)):
        r0, c0 = int(round(row)), int(round(col))
        rows, cols = np.mgrid[max(0, r0 - 6):min(image.shape[0], r0 + 7), max(0, c0 - 6):min(image.shape[1], c0 + 7)]
        window = image[rows, cols]
        centroids.append(((window * rows).sum() / window.sum(), (window * cols).sum() / window.sum()))
    return centroids


def test_thin_weak_lens_prescription_converges_to_the_thin_lens(args):
    """One very thin, weak biconvex lens (0.05 mm thick, f = 200 mm) behind a small stop (f/40)
    images points where the ideal thin lens of the same focal length does: 0.05 px. (Its clear
    apertures, 5.2 mm, keep its edge 0.016 mm thick: wider, its surfaces would cross, which is
    refused.)"""
    W, H = 160, 120
    pixel = 0.02
    n, R = 1.5, 200.0  # lensmaker: 1/f = (n - 1) 2 / R = 1/200 for a thin lens
    prescription = ("prescription { stop { thickness 0 aperture 5 } "
                    "surface { radius %r thickness 0.05 ior %r aperture 5.2 } "
                    "surface { radius %r thickness 0 ior 1 aperture 5.2 } } focus_distance 3" % (R, n, -R))
    points = [(x, y) for x in np.linspace(-0.019, 0.019, 4) for y in np.linspace(-0.014, 0.014, 3)]
    spheres = "".join("sphere { <%r, %r, 0>, 0.001 pigment { rgb 1 } finish { ambient 1 diffuse 0 } }\n" % p
                      for p in points)
    rest = "  sensor { pixel_size <%r, %r> } samples 256\n" % (pixel, pixel)
    real = pt.render(args.povray, args.work, "weak_prescription",
                     camera_scene(prescription, rest, background="rgb 0", objects=spheres), W, H, timeout=300)
    efl = pt.metadata_of(real)["main_lens"]["focal_length_mm"]
    # The thick-lens formula for this lens (independent of the camera's paraxial code).
    t = 0.05
    power = (n - 1) * (1 / R - 1 / -R + (n - 1) * t / (n * R * -R))
    assert efl == pytest.approx(1 / power, rel=1e-12)
    thin = pt.render(args.povray, args.work, "weak_thin_lens",
                     camera_scene("thin_lens focal_length %r aperture 5 focus_distance 3" % efl, rest,
                                  background="rgb 0", objects=spheres), W, H, timeout=300)
    a = blob_centroids(pt.read_linear(real).mean(axis=2), len(points))
    b = blob_centroids(pt.read_linear(thin).mean(axis=2), len(points))
    errors = [min(math.hypot(p[0] - q[0], p[1] - q[1]) for q in b) for p in a]
    assert max(errors) <= 0.05, errors


ARRAY_CASES = {
    # Pinhole microlenses: one sharp image of the sphere per pinhole its light reaches (Newton's
    # method in the projection). Thin microlenses at d = f (plenoptic 1.0): per lens, the patch of
    # the sphere's light that crosses that lens's cell (the centroid of the delivered light).
    "pinholes": "pinhole distance 0.5",
    "plenoptic-1.0": "focal_length 0.5 distance 0.5",
}


def hexagonal_neighbours(k, l):
    """The six neighbours of lens (k, l) in row form (odd rows shifted by half a pitch)."""
    shift = 0 if l % 2 else -1
    return [(k - 1, l), (k + 1, l), (k + shift, l - 1), (k + shift + 1, l - 1), (k + shift, l + 1), (k + shift + 1, l + 1)]


@pytest.mark.parametrize("case", sorted(ARRAY_CASES))
def test_forward_projection_with_array_matches_render(args, case):
    """Small bright spheres seen through the test lens and a hexagonal array, 13 degrees off axis
    (a sensor window offset from the axis, where the clear apertures start to clip the light):
    every image plenoptic-project predicts with the sphere wholly seen lies within 0.25 px of a
    rendered blob's centroid, and every rendered blob is a predicted image."""
    W, H, pixel = 320, 240, 0.005
    offset = (11.0, 7.0)  # mm: the window's centre, 13 mm off axis
    lens = reference_lens()
    par = lt.paraxial_data(lens)
    D = lt.paraxial_image_distance(lens, 3000.0)
    # Spheres 0.3 and 0.35 m in front of the lens, far from the focused plane (3 m): each point's
    # light spreads over about five lenses across; placed by the paraxial magnification so that
    # each lands in one half of the window. Small (0.25 mm), so that most lenses see all of one.
    radius_mm = 0.25
    centres = []
    for (du, z_m) in ((-0.4, 0.3), (0.4, 0.35)):
        image_x, image_y = -(offset[0] + du), -offset[1]  # the image is inverted
        magnification = (D + lens.length - par.rear_principal_z) / (z_m * 1000.0 + par.front_principal_z)
        centres.append((image_x / magnification / 1000.0, image_y / magnification / 1000.0, z_m - 3.0))
    spheres = "".join("sphere { <%r, %r, %r>, %r pigment { rgb 1 } finish { ambient 1 diffuse 0 } }\n"
                      % (c + (radius_mm / 1000.0,)) for c in centres)
    scene = camera_scene(inline_prescription() + " f_number 8 distance %r" % D,
                         "  microlens_array { hexagonal pitch 0.1 %s }\n"
                         "  sensor { pixel_size <%r, %r> offset <%r, %r> } samples 36\n"
                         % (ARRAY_CASES[case], pixel, pixel, offset[0], offset[1]),
                         background="rgb 0", objects=spheres)
    name = "real_lens_projection_" + case.replace(".", "_").replace("-", "_")
    path = pt.render(args.povray, args.work, name, scene, W, H, timeout=600)
    image = pt.read_linear(path)[..., :3].mean(axis=2)
    found = pt.blobs(image, 0.02)
    metadata = os.path.join(args.work, name + ".plenoptic.json")

    # Each sphere's centre and four points on its rim (across the line of sight): an image of the
    # centre is compared only when the lens and its six neighbours image all five, so that the
    # lens lies inside the light of the whole sphere (not at its rim, where the sphere is cut).
    probes = []
    for c in centres:
        r = radius_mm / 1000.0
        probes += [c, (c[0] + r, c[1], c[2]), (c[0] - r, c[1], c[2]), (c[0], c[1] + r, c[2]), (c[0], c[1] - r, c[2])]
    hits = pt.run_project(args.project, metadata, probes, fraction=True)
    by_probe = {}
    for index, k, l, u, v, fraction in hits:
        by_probe.setdefault(index, {})[(k, l)] = (u, v, fraction)
    compared, errors, missing = 0, [], []
    predicted = []
    for s in range(len(centres)):
        own = by_probe.get(5 * s, {})
        predicted += [(u, v) for (u, v, _) in own.values()]
        for probe in range(5 * s + 1, 5 * s + 5):
            predicted += [(u, v) for (u, v, _) in by_probe.get(probe, {}).values()]
        for lens_kl, (u, v, fraction) in own.items():
            whole = all(kl in by_probe.get(p, {}) for kl in [lens_kl] + hexagonal_neighbours(*lens_kl)
                        for p in range(5 * s, 5 * s + 5))
            if not whole or not (4 <= u <= W - 5 and 4 <= v <= H - 5):
                continue
            near = [b for b in found if math.hypot(b["u"] - u, b["v"] - v) <= 3]
            if not near:
                missing.append((s, lens_kl, round(u, 2), round(v, 2)))
                continue
            best = min(near, key=lambda b: math.hypot(b["u"] - u, b["v"] - v))
            errors.append(math.hypot(best["u"] - u, best["v"] - v))
            compared += 1
    assert compared >= 10, "only %d images wholly seen (hits %d, blobs %d)" % (compared, len(hits), len(found))
    assert not missing, missing[:5]
    print("%s: %d images compared, blob centroid - plenoptic-project: mean %.3f px, worst %.3f px"
          % (case, compared, sum(errors) / len(errors), max(errors)))
    assert max(errors) <= 0.25, sorted(errors)[-5:]
    # Every blob of some weight lies near a predicted image (of the centre or of a rim point).
    fluxes = sorted(b["flux"] for b in found)
    median = fluxes[len(fluxes) // 2]
    unexplained = [(round(b["u"], 1), round(b["v"], 1)) for b in found
                   if b["flux"] > 0.5 * median and not any(math.hypot(b["u"] - u, b["v"] - v) <= 4 for u, v in predicted)]
    assert not unexplained, unexplained[:5]


def test_depth_map_through_real_lens_matches_reference(args):
    """The depth map through the test lens (no array): per pixel, the distance (scene units) along
    its chief ray from where it leaves the front surface to a fronto-parallel wall, against the
    reference: the ray from the pixel centre through the centre of the paraxial exit pupil, traced
    through the lens by the reference tracer, met with the wall. Compared where the reference's ray
    passes every aperture (the camera ignores them for chief rays; so does the formula)."""
    W, H, pixel = 64, 48, 0.4  # a 25.6 x 19.2 mm sensor: about +-15 degrees
    lens = reference_lens()
    par = lt.paraxial_data(lens)
    D = lt.paraxial_image_distance(lens, 3000.0)
    wall_units = 1.0  # the wall at scene z = 1: 4 m in front of the front vertex
    scene = camera_scene(inline_prescription() + " f_number 8 distance %r" % D,
                         "  sensor { pixel_size <%r, %r> } samples 4 depth_map\n" % (pixel, pixel),
                         background="rgb 0",
                         objects="plane { z, %r pigment { rgb 1 } finish { ambient 1 diffuse 0 } }\n" % wall_units)
    path = pt.render(args.povray, args.work, "real_lens_depth", scene, W, H, timeout=300)
    depth = pt.read_pixels(os.path.join(args.work, "real_lens_depth.depth.exr"))[..., 0]
    assert depth.shape == (H, W)

    # Pixel centres on the sensor (optics frame: x right, y up, z = -D; pixel (i, j)'s centre at
    # x = -(i + 0.5 - W/2) pixel, y = (j + 0.5 - H/2) pixel: the image is inverted).
    i, j = np.meshgrid(np.arange(W), np.arange(H))
    sensor = np.stack([-(i + 0.5 - W / 2.0) * pixel, (j + 0.5 - H / 2.0) * pixel, np.full(i.shape, -D)], axis=-1)
    pupil = np.array([0.0, 0.0, lens.length - par.exit_pupil_z])
    result = lt.trace_image_to_object(lens, lt.optics_lens_mirror(sensor, lens),
                                      lt.optics_lens_mirror_directions(pupil - sensor))
    leave = lt.optics_lens_mirror(result.points, lens)
    towards = lt.optics_lens_mirror_directions(result.directions)
    wall_mm = (wall_units + 3.0) * 1000.0 + lens.length  # optics-frame z of the wall
    expected = (wall_mm - leave[..., 2]) / towards[..., 2] / 1000.0
    compared = result.passed
    assert compared.sum() >= 0.5 * W * H, compared.sum()
    error = np.abs(depth[compared] - expected[compared])
    print("depth through the real lens: %d pixels compared, largest difference %.2g scene units (of %.3f)"
          % (compared.sum(), error.max(), float(expected[compared].mean())))
    assert error.max() <= 1e-5 * expected[compared].max(), error.max()
    # Pixels whose chief ray the reference blocks still have a depth (apertures are ignored).
    assert np.all(np.isfinite(depth) & (depth > 0)), "every pixel has a depth"
