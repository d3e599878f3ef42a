# SPDX-License-Identifier: AGPL-3.0-or-later
"""The aperture that limits the axial beam (docs/real-lenses.md, "The aperture that limits the
beam"), against the reference tracer of the tests (plenoptic_testing.lens_tracer), on the 22 mm
f/3.5 wide-angle of lenses/ (Laikin's retrofocus design, 10 rows).

The reference side is worked here: the paraxial marginal ray from the axial object point of the
focused plane (lens_tracer's y-u trace), the aperture whose opening it fills first (smallest
ratio of opening radius to height), that aperture's pupils imaged as the reference images a stop,
the exact lit area of the exit pupil's plane, and the lit disc of a pinhole microimage.

- Written stop wider than the elements (30 mm; the lens's rims take over from about 15.4 mm): the
  render warns naming the limiting row, and the metadata's limiting surface, pupils, f-number,
  working f-number and microimage diameter are that rim's, equal to the reference's.
- The lit disc of the central pinhole microimage (its lit area, as an equivalent diameter)
  agrees with the metadata's microimage_diameter_px within 5 % (the real beam is narrower than
  the paraxial one by the pupil's spherical aberration, 3 % here); a white world's axial pixel
  without an array is the reference's exact lit area over the metadata's exit pupil (seen: lit
  disc 42.9 px against 43.6 px claimed; axial value 0.970). Before the limiting aperture was
  computed the metadata described the stop's pupil: f/1.41 and an 85.0 px microimage (the
  reference's paraxial data of the stop), and the axial value was the lit area over that pupil,
  0.255 (the reference's count).
- f_number 2.8 (stop-limited, near the lens's limit) and 3.5 agree the same way; f_number 2
  (a stop of 21 mm) is refused (tests/robustness/test_unreachable_apertures.py).
"""
import math
import os

import numpy as np
import pytest

import plenoptic_testing as pt
from plenoptic_testing import lens_tracer as lt

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
LENS_PATH = os.path.join(SOURCE, "lenses", "wide_angle_22mm_laikin_f3.5.dat")
FOCUS_M = 2.5
WIDE_STOP = 30.0


def lens_text(stop_diameter=None):
    """The lens file's text, with the stop row's diameter replaced when asked."""
    out = []
    for line in open(LENS_PATH).read().splitlines():
        fields = line.split("#")[0].split()
        if len(fields) == 4 and float(fields[0]) == 0.0 and stop_diameter is not None:
            line = "  0.0  %s  %s  %r  # stop, widened by the test" % (fields[1], fields[2], stop_diameter)
        out.append(line)
    return "\n".join(out) + "\n"


def stop_row_line(text):
    for number, line in enumerate(text.splitlines(), 1):
        fields = line.split("#")[0].split()
        if len(fields) == 4 and float(fields[0]) == 0.0:
            return number
    raise AssertionError("no stop row")


class Reference:
    """The reference's limiting aperture and its pupils for an axial object at `object_mm` in
    front of the front vertex (lens frame: z from the front vertex towards the image)."""

    def __init__(self, lens, object_mm):
        self.lens = lens
        count = len(lens.surfaces)
        heights = [lt._paraxial_ray(lens, 0.0, 1.0, -object_mm, range(i), lens.vertex_z[i])[0] for i in range(count)]
        ratios = [lens.opening_radius(i) / abs(h) for i, h in enumerate(heights)]
        stop = lens.stop_index
        rim = min((i for i in range(count) if i != stop), key=lambda i: ratios[i])
        self.limiting = rim if ratios[rim] < ratios[stop] * (1 - 0.005) else stop
        self.largest_stop = 2.0 * abs(heights[stop]) * ratios[rim]
        a = self.limiting
        z_a, radius = lens.vertex_z[a], lens.opening_radius(a)
        # Entrance pupil: rays of object space traced to the aperture's plane (as lt.paraxial_data
        # does for the stop): height y h1 + u h2 there.
        h1, _ = lt._paraxial_ray(lens, 1.0, 0.0, 0.0, range(a), z_a)
        h2, _ = lt._paraxial_ray(lens, 0.0, 1.0, 0.0, range(a), z_a)
        self.entrance_pupil_z = h2 / h1
        self.entrance_pupil_diameter = 2.0 * radius / abs(h1)
        # Exit pupil: rays leaving a point of the aperture (in the medium after it) through the
        # surfaces behind it.
        L = lens.length
        after = range(a + 1, count)
        edge_height, edge_slope = lt._paraxial_ray(lens, 1.0, 0.0, z_a, after, L)
        chief_height, chief_slope = lt._paraxial_ray(lens, 0.0, 1.0, z_a, after, L)
        self.exit_pupil_z = L - chief_height / chief_slope
        self.exit_pupil_diameter = 2.0 * radius * abs(edge_height + edge_slope * (self.exit_pupil_z - L))
        self.efl = lt.paraxial_data(lens).efl
        self.f_number = self.efl / self.entrance_pupil_diameter


def camera(main, rest):
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 1 }\n"
            "camera { plenoptic location <0, 0, -3> look_at <0, 0, 0>\n"
            "  main_lens { %s focus_distance %r }\n%s}\n" % (main, FOCUS_M, rest))


# A pinhole array whose central microimage (about 40 px across) lies whole in a 64 x 64 picture.
PITCH, GAP, PIXEL, SIZE = 0.32, 0.6, 0.005, 64
ARRAY = ("  microlens_array { rectangular pitch %r pinhole distance %r }\n"
         "  sensor { pixel_size <%r, %r> } samples 16\n" % (PITCH, GAP, PIXEL, PIXEL))


def render_case(args, name, main, rest, width, height, text=None):
    if text is not None:
        pt.write_text(os.path.join(args.work, name + ".dat"), text)
    scene = camera(main, rest)
    pov = os.path.join(args.work, name + ".pov")
    out = os.path.join(args.work, name + ".png")
    pt.write_text(pov, scene)
    pt.remove_outputs(args.work, name, "png")
    run = pt.run_process([args.povray, "+I" + pov, "+O" + out, "+W%d" % width, "+H%d" % height, "+L" + args.work]
                         + list(pt.LINEAR16), cwd=args.work, timeout=300)
    assert run.returncode == 0 and os.path.exists(out), run.output[-3000:]
    return out, pt.metadata_of(out), run.output


def check_metadata(meta, ref, lens):
    main = meta["main_lens"]
    par = main["paraxial"]
    L = lens.length
    D = main["distance_mm"]
    assert D == pytest.approx(lt.paraxial_image_distance(lens, FOCUS_M * 1000.0), rel=1e-12)
    assert par["limiting_surface"] == ref.limiting
    expected = {
        "entrance_pupil_z_mm": L - ref.entrance_pupil_z,
        "entrance_pupil_diameter_mm": ref.entrance_pupil_diameter,
        "exit_pupil_z_mm": L - ref.exit_pupil_z,
        "exit_pupil_diameter_mm": ref.exit_pupil_diameter,
        "f_number": ref.f_number,
        "working_f_number": (L - ref.exit_pupil_z + D) / ref.exit_pupil_diameter,
        "largest_stop_diameter_mm": ref.largest_stop,
    }
    wrong = {k: (par[k], v) for k, v in expected.items() if par[k] != pytest.approx(v, rel=1e-9)}
    assert not wrong, wrong
    assert main["f_number"] == pytest.approx(ref.f_number, rel=1e-9)
    return D


def lit_disc_px(image):
    """Equivalent diameter (px) of the lit area of the picture (one microimage; value = lit
    fraction of each pixel's area)."""
    return 2.0 * math.sqrt(image.sum() / math.pi)


@pytest.mark.parametrize("case", ["wide_stop", "f2.8", "f3.5"])
def test_microimage_and_metadata_follow_the_limiting_aperture(args, case):
    if case == "wide_stop":
        text = lens_text(WIDE_STOP)
        lens = lt.Lens(lt.parse_lens_file(text))
        main = 'lens_file "limiting_%s.dat"' % case
    else:
        text = lens_text()
        n = float(case[1:])
        base = lt.Lens(lt.parse_lens_file(text))
        paraxial = lt.paraxial_data(base)
        # f_number N sizes the stop so that efl / entrance pupil = N; the entrance pupil scales with it.
        stop = base.stop_diameter * paraxial.f_number / n
        lens = lt.Lens(base.surfaces, stop_diameter=stop)
        main = 'lens_file "limiting_%s.dat" f_number %r' % (case, n)
    ref = Reference(lens, FOCUS_M * 1000.0)
    assert (ref.limiting != lens.stop_index) == (case == "wide_stop"), (case, ref.limiting)

    path, meta, output = render_case(args, "limiting_" + case, main, ARRAY, SIZE, SIZE, text)
    output = " ".join(output.split())  # POV-Ray wraps its messages at 80 columns
    D = check_metadata(meta, ref, lens)
    warned = "wider than the lens can use" in output
    assert warned == (case == "wide_stop"), output[-2000:]
    if warned:
        # The warning names the limiting row of the lens file and its line there.
        row = ref.limiting + 1
        line = [n for n, l in enumerate(text.splitlines(), 1) if len(l.split("#")[0].split()) == 4][ref.limiting]
        assert "surface %d (line %d of lens_file" % (row, line) in output, output[-2000:]
        assert "the stop (surface %d, line %d of lens_file" % (lens.stop_index + 1, stop_row_line(text)) in output

    claimed = meta["microimage_lattice"]["microimage_diameter_px"]
    paraxial_disc = ref.exit_pupil_diameter * GAP / (lens.length - ref.exit_pupil_z + D) / PIXEL
    assert claimed == pytest.approx(paraxial_disc, rel=1e-9)
    image = pt.read_linear(path)[..., :3].mean(axis=2)
    pt.save_png(os.path.join(args.work, "limiting_%s_view.png" % case), image)
    lit = lit_disc_px(image)
    # The real beam is narrower than the paraxial one (the pupils' spherical aberration: 3 % here).
    assert lit == pytest.approx(claimed, rel=0.05), (lit, claimed)
    assert lit <= claimed * 1.005, (lit, claimed)


def test_white_world_axis_reads_the_lit_share_of_the_limiting_pupil(args):
    """No array: a white world's axial pixel is the lit area of the exit pupil's plane over the
    paraxial exit pupil's area (docs/real-lenses.md, "Sampling without an array"): the reference's
    exact count of the rays from the axial point that pass, on the plane of the metadata's exit
    pupil."""
    text = lens_text(WIDE_STOP)
    lens = lt.Lens(lt.parse_lens_file(text))
    ref = Reference(lens, FOCUS_M * 1000.0)
    W = H = 8
    pixel = 0.01
    path, meta, _ = render_case(args, "limiting_bare", 'lens_file "limiting_bare.dat"',
                                "  sensor { pixel_size <%r, %r> } samples 4\n" % (pixel, pixel), W, H, text)
    D = check_metadata(meta, ref, lens)
    axis = pt.read_linear(path)[..., :3].mean(axis=2)[H // 2 - 1:H // 2 + 1, W // 2 - 1:W // 2 + 1].mean()
    # The reference's count on the plane of the stop's paraxial exit pupil, carried to the
    # limiting aperture's: the cone from an axial point scales with the distance from it.
    stop_pupil = lt.paraxial_data(lens)
    sensor_z = lens.length + D
    points = [(sx * pixel / 2, sy * pixel / 2) for sx in (-1, 1) for sy in (-1, 1)]
    on_stop_plane = lt.relative_lit_area_no_array(lens, D, points, 400).mean() * math.pi * (stop_pupil.exit_pupil_diameter / 2) ** 2
    scale = (sensor_z - ref.exit_pupil_z) / (sensor_z - stop_pupil.exit_pupil_z)
    expected = on_stop_plane * scale ** 2 / (math.pi * (ref.exit_pupil_diameter / 2) ** 2)
    assert 0.85 < expected < 1.0, expected
    assert axis == pytest.approx(expected, abs=0.01), (axis, expected)
