# SPDX-License-Identifier: AGPL-3.0-or-later
"""The catalogue's double-Gauss (lenses/double_gauss_50mm_tronnier_f2.dat: Tronnier,
US 2,673,491, as printed in W. J. Smith, Modern Lens Design, p. 312, scaled to 50 mm) rendered
through its catalogue name, against the independent reference tracer of the tests
(plenoptic_testing.lens_tracer), which reads the same file from the source tree.

- Paraxial data: the metadata's EFL, back and front focus, length, principal planes and the gap D
  of the lens focused at 3 m equal the reference's y-u trace; its pupils, f-number and working
  f-number are those of the aperture that limits the axial beam, worked out here from the
  reference's paraxial marginal ray: at f_number 2.8 the stop, at full aperture (the stop as
  printed, 17.1 mm) the rim of surface 3 (23 mm), which the paraxial marginal ray fills 2 % before
  the stop (the render warns, naming it).
- White image at full aperture with pinhole microlenses: every sensor point has one ray through
  each pinhole, so a pixel's value in a white scene is the fraction of its area whose ray passes
  the whole lens; the reference counts it on an 8 x 8 grid per pixel, the camera with its own
  samples. Towards the corners the printed clear apertures clip the microimages into cat's eyes,
  and the two images must agree pixel by pixel within the sampling error of the two estimates.
"""
import os

import numpy as np
import pytest

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
NAME = "double_gauss_50mm_tronnier_f2.dat"
FOCUS_M = 3.0


def reference_lens(stop_diameter=None):
    with open(os.path.join(SOURCE, "lenses", NAME)) as f:
        return lt.Lens(lt.parse_lens_file(f.read()), stop_diameter=stop_diameter)


def limiting_pupils(lens, object_mm):
    """The aperture that limits the axial beam from the axial point object_mm in front of the
    front vertex (the smallest ratio of opening radius to paraxial marginal-ray height; the stop
    unless a rim's ratio is smaller by more than 0.5 %, the rounding allowed to printed
    diameters), and its pupils: (index, entrance pupil z, its diameter, exit pupil z, its
    diameter), lens frame."""
    count = len(lens.surfaces)
    heights = [lt._paraxial_ray(lens, 0.0, 1.0, -object_mm, range(i), lens.vertex_z[i])[0] for i in range(count)]
    ratios = [lens.opening_radius(i) / abs(h) for i, h in enumerate(heights)]
    stop = lens.stop_index
    rim = min((i for i in range(count) if i != stop), key=lambda i: ratios[i])
    a = rim if ratios[rim] < ratios[stop] * (1 - 0.005) else stop
    z_a, radius, L = lens.vertex_z[a], lens.opening_radius(a), lens.length
    h1, _ = lt._paraxial_ray(lens, 1.0, 0.0, 0.0, range(a), z_a)
    h2, _ = lt._paraxial_ray(lens, 0.0, 1.0, 0.0, range(a), z_a)
    edge_height, edge_slope = lt._paraxial_ray(lens, 1.0, 0.0, z_a, range(a + 1, count), L)
    chief_height, chief_slope = lt._paraxial_ray(lens, 0.0, 1.0, z_a, range(a + 1, count), L)
    exit_z = L - chief_height / chief_slope
    return a, h2 / h1, 2.0 * radius / abs(h1), exit_z, 2.0 * radius * abs(edge_height + edge_slope * (exit_z - L))


def scene(main, rest):
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 1 }\n"
            "camera { plenoptic location <0, 0, -3> look_at <0, 0, 0>\n"
            "  main_lens { lens_file \"%s\" %s focus_distance %r }\n%s}\n" % (NAME, main, FOCUS_M, rest))


def render(args, name, main, rest, width, height, timeout=300):
    """Renders by the lens's catalogue name (the program's own lenses/ folder); returns the
    image's path, its metadata and the console text."""
    pov, out = os.path.join(args.work, name + ".pov"), os.path.join(args.work, name + ".png")
    pt.write_text(pov, scene(main, rest))
    pt.remove_outputs(args.work, name, "png")
    run = pt.run_process([args.povray, "+I" + pov, "+O" + out, "+W%d" % width, "+H%d" % height]
                         + list(pt.LINEAR16), cwd=args.work, timeout=timeout)
    assert run.returncode == 0 and os.path.exists(out), run.output[-3000:]
    return out, pt.metadata_of(out), run.output


@pytest.mark.parametrize("f_number", [None, 2.8])
def test_paraxial_data_in_metadata(args, f_number):
    main = "" if f_number is None else "f_number %r" % f_number
    _, meta, output = render(args, "double_gauss_paraxial_%s" % ("full" if f_number is None else f_number), main,
                             "  sensor { pixel_size <0.5, 0.5> } samples 1\n", 16, 12)
    lens = reference_lens()
    ref = lt.paraxial_data(lens)
    if f_number is not None:
        # The stop scaled so that its entrance pupil is EFL / N (the pupil scales with the stop).
        lens = reference_lens(stop_diameter=lens.opening_radius(lens.stop_index) * 2.0 * ref.f_number / f_number)
    L = lens.length
    D = lt.paraxial_image_distance(lens, FOCUS_M * 1000.0)
    limiting, ep_z, ep_d, xp_z, xp_d = limiting_pupils(lens, FOCUS_M * 1000.0)
    main_lens = meta["main_lens"]
    par = main_lens["paraxial"]
    assert main_lens["type"] == "prescription" and main_lens["prescription"]["lens_file"] == NAME
    # At full aperture surface 3's rim (index 2) limits the beam, and the render says so; at f/2.8
    # the stop does.
    assert limiting == (2 if f_number is None else lens.stop_index), limiting
    if f_number is None:
        said = " ".join(output.split())  # the console wraps its lines
        assert "surface 3 (line" in said and "wider than the lens can use" in said, output[-3000:]
    expected = {
        "effective_focal_length_mm": ref.efl, "back_focal_distance_mm": ref.bfd,
        "front_focal_distance_mm": ref.ffd, "length_mm": L,
        # optics frame: z from the rear vertex towards the scene
        "front_principal_plane_z_mm": L - ref.front_principal_z,
        "rear_principal_plane_z_mm": L - ref.rear_principal_z,
        "limiting_surface": limiting,
        "entrance_pupil_z_mm": L - ep_z, "entrance_pupil_diameter_mm": ep_d,
        "exit_pupil_z_mm": L - xp_z, "exit_pupil_diameter_mm": xp_d,
        "f_number": ref.efl / ep_d, "working_f_number": (L - xp_z + D) / xp_d,
    }
    wrong = {k: (par[k], v) for k, v in expected.items() if par[k] != pytest.approx(v, rel=1e-9, abs=1e-12)}
    assert not wrong, wrong
    assert main_lens["distance_mm"] == pytest.approx(D, rel=1e-12)
    assert main_lens["focal_length_mm"] == pytest.approx(ref.efl, rel=1e-12)
    # The catalogue's figures (lenses/README.md): EFL 50.358 mm, back focus 36.106 mm; at full
    # aperture the lens works at f/2.073 (the rim), at f/2.8 as asked.
    assert ref.efl == pytest.approx(50.358, abs=0.0005) and ref.bfd == pytest.approx(36.106, abs=0.0005)
    assert main_lens["f_number"] == pytest.approx(2.073 if f_number is None else f_number, abs=0.0005)


def test_white_image_full_aperture_pinhole_array_matches_reference(args):
    """Cat's-eye microimages through the double-Gauss at full aperture, pixel by pixel."""
    W = H = 120
    pixel = 0.5          # mm: a 60 mm square sensor, a field of up to 40 degrees, past the design's 22
    pitch, d = 5.0, 7.0  # mm: d / p = 1.4, below the working f-number (2.09): no overlap
    samples = 64
    path, meta, _ = render(args, "double_gauss_white", "",
                           "  microlens_array { rectangular pitch %r pinhole distance %r }\n"
                           "  sensor { pixel_size <%r, %r> } samples %d\n" % (pitch, d, pixel, pixel, samples),
                           W, H, timeout=300)
    rendered = pt.read_linear(path)[..., :3].mean(axis=2)
    lens = reference_lens()
    D = meta["main_lens"]["distance_mm"]
    assert D == pytest.approx(lt.paraxial_image_distance(lens, FOCUS_M * 1000.0), rel=1e-12)
    expected = lt.white_image_pinhole_array(lens, D, d, pitch, W, H, pixel, pixel, 8)
    pt.save_png(os.path.join(args.work, "double_gauss_white_expected.png"), expected)

    # The cat's eyes are there: the corners' microimages are clipped or dark.
    centre_lit = expected[H // 2 - 15:H // 2 + 15, W // 2 - 15:W // 2 + 15].mean()
    corner_lit = expected[:20, :20].mean()
    assert corner_lit < 0.5 * centre_lit, (corner_lit, centre_lit)

    diff = np.abs(rendered - expected)
    print("double-Gauss white image, render - reference: max %.4f, 99th percentile %.4f, means %.5f %.5f"
          % (diff.max(), np.percentile(diff, 99), rendered.mean(), expected.mean()))
    # Two estimates of a pixel's lit fraction (64 camera samples and its vignetting probes against
    # the reference's 64-point grid) differ only at microimage rims, by a few samples' worth; a
    # wrong gap, pupil or clear aperture moves whole rims, by up to 1.
    assert diff.max() <= 0.1, diff.max()
    assert np.percentile(diff, 99) <= 0.05, np.percentile(diff, 99)
    assert abs(rendered.mean() - expected.mean()) <= 0.002, (rendered.mean(), expected.mean())
