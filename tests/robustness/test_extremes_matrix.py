# SPDX-License-Identifier: AGPL-3.0-or-later
"""The extremes matrix: tiny renders at the edges of every parameter.

Each case is either RENDERED or REFUSED, as the table below says and why.

A RENDERED case must, within its time limit:
  - exit 0 on an OpenEXR render (+FE +UA, one thread) and on a second one with two threads,
    with bit-identical float pixels (the same image whatever the thread count, run to run);
  - have no NaN or infinite value in any channel (read back with OpenImageIO);
  - show light somewhere: the scene has a sky everywhere, so an all-black image means every ray
    was lost (NaN rays turn black in POV-Ray, so this is what catches them);
    cases whose geometry blocks most light say so with a lower `lit` bound;
  - exit 0 on a PNG render of the same size, with a metadata JSON beside it that holds no
    NaN or Infinity and names the image size.
Cases that are a hair away from another case (d = f(1 +- 1e-12) next to d = f, a 1e-9 degree
rotation next to none, focus at 1e9 units next to distance = F) must also give the same image
as that case up to the pixels whose samples lie on a lattice border (`like`, at most 2 % of
the pixels differ by more than 1e-3).

A REFUSED case must exit non-zero by itself (no signal, no time-out) with POV-Ray's
`File '...' line N` parse error and the expected words.
"""
import os
import shutil

import numpy as np
import pytest

import plenoptic_testing as pt

PLACE = "  location <0, 0.4, -2>\n  look_at <0, 0.3, 0>\n"


def cam(*parts, samples="  samples 2"):
    body = "\n".join(parts)
    return "camera {\n  plenoptic\n" + PLACE + body + "\n" + (samples + "\n" if samples else "") + "}\n"


def thin(F=16, N=4, focus=2, D=None):
    where = "distance %r" % D if D is not None else "focus_distance %r" % focus
    return "  main_lens { thin_lens focal_length %r f_number %r %s }" % (F, N, where)


def hexa(p=0.08, f=0.32, d=0.32, grid="hexagonal", pose=""):
    lens = "pinhole" if f is None else "focal_length %r" % f
    return "  microlens_array { %s pitch %r %s distance %r %s}" % (grid, p, lens, d, pose + " " if pose else "")


def sensor(px=0.01, offset=None):
    off = " offset <%r, %r>" % offset if offset else ""
    size = "<%r, %r>" % px if isinstance(px, tuple) else repr(px)
    return "  sensor { pixel_size %s%s }" % (size, off)


W, H = 24, 18

# Exactly representable values for the lattice-border cases: pixel 2^-7 mm, offset 2^-8 mm, so
# every pixel centre lies on a multiple of 2^-7 mm (half of them on cell borders of a 2^-6 pitch).
PX2 = 0.0078125
OFF2 = 0.00390625

# name: (camera block, expectation, why, options)
# options: w, h (image size), lit (lowest fraction of non-black pixels), like (case it must match),
#          refuse (words of the refusal), timeout (s)
CASES = [
    ("d = f exactly (plenoptic 1.0)", cam(thin(), hexa(d=0.32), sensor()), "rendered",
     "d = f gives parallel rays behind each microlens; the optics have no division there", {}),
    ("d = f (1 + 1e-12)", cam(thin(), hexa(d=0.32 * (1 + 1e-12)), sensor()), "rendered",
     "a hair from d = f: must not blow up, and must look like d = f", {"like": "d = f exactly (plenoptic 1.0)"}),
    ("d = f (1 - 1e-12)", cam(thin(), hexa(d=0.32 * (1 - 1e-12)), sensor()), "rendered",
     "the other side of d = f", {"like": "d = f exactly (plenoptic 1.0)"}),
    ("main D = F exactly (focus at infinity)", cam(thin(D=16), hexa(), sensor()), "rendered",
     "D = F: the main lens focuses at infinity; no conjugate, no division", {}),
    ("focus at 1e9 scene units", cam(thin(focus=1e9), hexa(), sensor()), "rendered",
     "D = F / (1 - F/z) tends to F without overflow", {"like": "main D = F exactly (focus at infinity)"}),
    ("focus at 1e9 units, mm_per_unit 1e9", cam("  mm_per_unit 1e9", thin(focus=1e9), hexa(), sensor()), "rendered",
     "z = 1e18 mm: still finite (not like D = F: at this scale the 4 mm aperture is a pinhole in the scene)", {}),
    ("main focal length 1e-6 mm", cam(thin(F=1e-6), hexa(), sensor()), "rendered",
     "a 1e-6 mm lens focused at 2 m sits 1e-6 mm from the array: only ~1e-11 of each lens cell sends light "
     "into its 2.5e-7 mm aperture, so the right value is black; finite, no NaN", {"lit": 0.0}),
    ("main focal length 1e6 mm, focus inside it", cam(thin(F=1e6), hexa(), sensor()), "refused",
     "focus_distance 2 m = 2000 mm is inside F = 1e6 mm: no real image",
     {"refuse": ["focus_distance", "inside the focal length"]}),
    ("main focal length 1e6 mm, focus at 1e4 units", cam(thin(F=1e6, focus=1e4), hexa(), sensor()), "rendered",
     "a 1 km telephoto focused at 10 km: tiny field of view, finite rays", {}),
    ("microlens focal length 1e-6 mm", cam(thin(), hexa(f=1e-6), sensor()), "rendered",
     "extremely strong microlenses: rays fan out, many miss the main lens (black), none NaN", {"lit": 0.0}),
    ("microlens focal length 1e6 mm", cam(thin(), hexa(f=1e6), sensor()), "rendered",
     "microlenses that barely bend: nearly a pinhole-free plain camera", {}),
    ("bare array, microlens focal length 1e-6 mm", cam(hexa(f=1e-6), sensor()), "rendered",
     "no main lens: every ray leaves the array, nothing blocks it", {}),
    ("pitch of one pixel", cam(thin(), hexa(p=0.01, f=0.04, d=0.04), sensor()), "rendered",
     "one pixel per microimage: legal, warned (no angular resolution)", {}),
    ("pitch of the whole sensor (one lens)", cam(thin(), hexa(p=1.0, f=0.32, d=0.32, grid="rectangular"), sensor()), "rendered",
     "a single lens covers the sensor: one microimage, the main-lens disc", {"lit": 0.05}),
    ("rotate 0 degrees about z", cam(thin(), hexa(pose="rotate <0, 0, 0>"), sensor()), "rendered",
     "the reference of the rotations", {}),
    ("rotate 1e-9 degrees about z", cam(thin(), hexa(pose="rotate <0, 0, 1e-9>"), sensor()), "rendered",
     "a rotation that moves lens centres by ~1e-11 mm must look like none", {"like": "rotate 0 degrees about z"}),
    ("rotate 45 degrees about z", cam(thin(), hexa(pose="rotate <0, 0, 45>"), sensor()), "rendered",
     "in-plane rotation: the lookup goes through the pose", {}),
    ("rotate 89.99 degrees about z", cam(thin(), hexa(pose="rotate <0, 0, 89.99>"), sensor()), "rendered",
     "in-plane rotation just below a quarter turn", {}),
    # One sample each: an untilted array aims several samples where light passes (camera/aim.h), a
    # tilted one does not, so at 2 samples the two differ by their samplers' noise; one sample is the
    # pixel's chief ray through both.
    ("rotate 0 degrees about z, 1 sample", cam(thin(), hexa(pose="rotate <0, 0, 0>"), sensor(), samples="  samples 1"),
     "rendered", "the reference of the tilts", {}),
    ("tilt 1e-9 degrees about x", cam(thin(), hexa(pose="rotate <1e-9, 0, 0>"), sensor(), samples="  samples 1"),
     "rendered", "a tilt of 1e-9 degrees takes the tilted code paths but must look like none",
     {"like": "rotate 0 degrees about z, 1 sample"}),
    ("tilt 45 degrees about x", cam(thin(), hexa(pose="rotate <45, 0, 0>"), sensor()), "rendered",
     "a strongly tilted array: legal (below 90 degrees)", {}),
    ("tilt 89.99 degrees about y", cam(thin(), hexa(pose="rotate <0, 89.99, 0>"), sensor()), "rendered",
     "nearly edge-on: rays graze the array; most light is lost, nothing is NaN", {"lit": 0.0}),
    ("tilt 90 degrees about x", cam(thin(), hexa(pose="rotate <90, 0, 0>"), sensor()), "refused",
     "edge-on: no light passes", {"refuse": ["rotate", "edge-on"]}),
    ("sensor offset at the sensor corner", cam(thin(), hexa(), sensor(offset=(0.12, 0.09))), "rendered",
     "the optical axis meets the sensor at its corner (principal point at pixel (-0.5, -0.5))", {}),
    ("sensor offset at the edge, no array", cam(thin(), sensor(offset=(0.12, 0.0))), "rendered",
     "a shifted plain thin-lens camera", {}),
    ("sensor offset 1e6 mm", cam(thin(), hexa(), sensor(offset=(1e6, 0.0))), "rendered",
     "a sensor a kilometre off-axis: each pixel's own lens is on its line to the main-lens centre, so light "
     "still passes; the camera looks sideways at a grazing angle", {}),
    ("mm_per_unit 1e-6, distance-placed lens", cam("  mm_per_unit 1e-6", thin(D=16.5), hexa(), sensor()), "rendered",
     "one scene unit is a nanometre: the aperture spans millions of units; finite rays", {}),
    ("mm_per_unit 1e-6 with focus_distance 2", cam("  mm_per_unit 1e-6", thin(), hexa(), sensor()), "refused",
     "2 units = 2e-6 mm is inside the 16 mm focal length", {"refuse": ["focus_distance", "inside the focal length"]}),
    ("mm_per_unit 1e9", cam("  mm_per_unit 1e9", thin(), hexa(), sensor()), "rendered",
     "one scene unit is 1000 km: focus at 2e9 mm, D ~ F", {}),
    ("1x1 image", cam(thin(), hexa(), sensor()), "rendered",
     "a single pixel", {"w": 1, "h": 1}),
    ("4000x1 image", cam(thin(), hexa(), sensor(), samples="  samples 1"), "rendered",
     "a 40 mm x 0.01 mm sensor strip", {"w": 4000, "h": 1}),
    ("1x300 image, no array", cam(thin(), sensor()), "rendered",
     "a tall strip", {"w": 1, "h": 300}),
    ("1000000 samples on 1x1", cam(thin(), hexa(), sensor(), samples="  samples 1000000"), "rendered",
     "the largest sample count, bounded", {"w": 1, "h": 1, "timeout": 120}),
    # The adaptive minimum is 2 (one sample has no variance; `samples 1, N` is refused, and with
    # it a pixel stopped after one ray). 10^4 rays run to the maximum in seconds.
    ("adaptive 2 to 10000, tiny variance, 1x1", cam(thin(), hexa(), sensor(), samples="  samples 2, 10000\n  confidence 0.999999\n  variance 1e-300"), "rendered",
     "adaptive sampling that never converges stops at the maximum", {"w": 1, "h": 1, "timeout": 120}),
    ("pixel centres on rectangular cell borders, no main lens",
     cam(hexa(p=2 * PX2, f=None, d=0.05, grid="rectangular"), sensor(px=PX2, offset=(OFF2, OFF2)), samples="  samples 1"), "rendered",
     "half the pixel centres lie exactly on a border (binary-exact numbers); either lens is right, the same every run", {}),
    ("pixel centres on rectangular cell borders, thin main lens",
     cam(thin(N=2048, D=16.0), hexa(p=PX2, f=16.0, d=16.0, grid="rectangular"), sensor(px=PX2, offset=(OFF2, OFF2)), samples="  samples 1"), "rendered",
     "D = d: the central projection halves sensor coordinates exactly, so the borders stay exact "
     "(f_number 2048 keeps the microimages apart, so pixels between microimages are dark: a quarter lit)",
     {"lit": 0.2}),
    ("pixel centres on hexagonal cell borders, no main lens",
     cam(hexa(p=2 * PX2, f=None, d=0.05), sensor(px=PX2, offset=(OFF2, OFF2)), samples="  samples 4"), "rendered",
     "vertical borders between the lenses of a row are exact", {}),
    ("pinhole main lens, microlens 1e-9 from degenerate", cam("  main_lens { pinhole distance 2 }", hexa(p=0.08, f=1 + 1e-9, d=2, grid="rectangular"), sensor()), "rendered",
     "1/D + 1/d = 1/f within 1e-9: no division by it, rays are only blocked", {"lit": 0.0}),
    ("pinhole main lens, microlens 1e-13 from degenerate", cam("  main_lens { pinhole distance 2 }", hexa(p=0.08, f=1 + 1e-13, d=2, grid="rectangular"), sensor()), "refused",
     "within the 1e-12 tolerance of 1/D + 1/d = 1/f: degenerate", {"refuse": ["degenerate"]}),
]


def render(povray, case_dir, scene, out, w, h, extra, timeout):
    return pt.run_povray(povray, scene, os.path.join(case_dir, out), w, h, extra, timeout=timeout, cwd=case_dir)


def check_rendered(povray, case_dir, w, h, opts, results, name):
    problems = []
    timeout = opts.get("timeout", 60)
    images = []
    for threads in (1, 2):
        out = "t%d.exr" % threads
        run = render(povray, case_dir, "case.pov", out, w, h, ["+FE", "+UA", "+WT%d" % threads], timeout)
        crash = pt.crash_reason(run)
        if crash or run.returncode != 0:
            problems.append("EXR render (%d thread%s): %s\n%s" % (threads, "s" if threads > 1 else "",
                            crash or "exit %d" % run.returncode, pt.tail(run.output)))
            return problems, None
        images.append(pt.read_pixels(os.path.join(case_dir, out)))
    a, b = images
    if a.shape != (h, w, a.shape[2]):
        problems.append("EXR is %s, expected %dx%d" % (a.shape, w, h))
    bad = ~np.isfinite(a)
    if bad.any():
        ys, xs, cs = np.nonzero(bad)
        problems.append("%d non-finite values, first at pixel (%d, %d) channel %d: %r" %
                        (bad.sum(), xs[0], ys[0], cs[0], a[ys[0], xs[0], cs[0]]))
    if not np.array_equal(a, b, equal_nan=True):
        diff = np.nonzero(np.any(a != b, axis=2))
        problems.append("1 thread and 2 threads differ in %d pixels (first (%d, %d): %s vs %s)" %
                        (len(diff[0]), diff[1][0], diff[0][0], a[diff[0][0], diff[1][0]], b[diff[0][0], diff[1][0]]))
    lit = float(np.mean(np.any(np.nan_to_num(a[:, :, :3]) > 1e-6, axis=2)))
    need = opts.get("lit", 0.5)
    if lit < need or (need > 0 and lit == 0):
        problems.append("only %.1f%% of pixels receive light, expected at least %.0f%% (the sky is everywhere)" %
                        (100 * lit, 100 * need))
    run = render(povray, case_dir, "case.pov", "t.png", w, h, ["+FN8", "+WT2"], timeout)
    crash = pt.crash_reason(run)
    if crash or run.returncode != 0:
        problems.append("PNG render: %s\n%s" % (crash or "exit %d" % run.returncode, pt.tail(run.output)))
    else:
        png = os.path.join(case_dir, "t.png")
        meta = os.path.join(case_dir, "t.plenoptic.json")
        if not os.path.exists(png):
            problems.append("no PNG written")
        if not os.path.exists(meta):
            problems.append("no metadata JSON beside the PNG")
        else:
            try:
                data = pt.load_metadata(meta)
                if data.get("image") != {"width": w, "height": h}:
                    problems.append("metadata image %r, expected %dx%d" % (data.get("image"), w, h))
            except ValueError as e:
                problems.append("metadata JSON: %s" % e)
    results[name] = a
    return problems, lit


def check_refused(povray, case_dir, w, h, opts):
    run = render(povray, case_dir, "case.pov", "t.png", w, h, ["+FN8", "+WT1"], opts.get("timeout", 60))
    problems, err = pt.refusal_problems(run)
    if err is not None:
        missing = [w_ for w_ in opts["refuse"] if w_.lower() not in err[2].lower()]
        if missing:
            problems.append("message lacks %s: %r" % (missing, err[2]))
    if any(os.path.exists(os.path.join(case_dir, f)) for f in ("t.png", "t.plenoptic.json")):
        problems.append("left an image or metadata behind")
    if problems:
        problems.append(pt.tail(run.output, 8))
    return problems, err


# name -> the EXR of a rendered case (the reference of the cases that name it in `like`).
RESULTS = {}


def run_case(args, index):
    """Renders or refuses case `index` in its own folder; (problems, detail)."""
    name, block, expect, why, opts = CASES[index]
    case_dir = os.path.join(args.work, "case%02d" % index)
    shutil.rmtree(case_dir, ignore_errors=True)
    os.makedirs(case_dir)
    pt.write_scene(os.path.join(case_dir, "case.pov"), block)
    w, h = opts.get("w", W), opts.get("h", H)
    if expect == "rendered":
        problems, lit = check_rendered(args.povray, case_dir, w, h, opts, RESULTS, name)
        like = opts.get("like")
        if not problems and like:
            if like not in RESULTS:  # the reference case alone (pytest -k)
                run_case(args, [c[0] for c in CASES].index(like))
            if like not in RESULTS:
                problems.append("reference case %r did not render" % like)
            else:
                ref = RESULTS[like]
                cur = RESULTS[name]
                differs = np.any(np.abs(cur - ref) > 1e-3, axis=2)
                frac = float(np.mean(differs))
                if frac > 0.02:
                    problems.append("differs from %r in %.1f%% of pixels (> 2%%); max difference %.4g" %
                                    (like, 100 * frac, float(np.max(np.abs(cur - ref)))))
        detail = "lit %.0f%%" % (100 * lit) if lit is not None else ""
    else:
        problems, err = check_refused(args.povray, case_dir, w, h, opts)
        detail = ("line %d: %s" % (err[1], err[2][:90])) if err else ""
    return problems, detail


@pytest.mark.parametrize("index", range(len(CASES)), ids=[c[0] for c in CASES])
def test_extremes(args, index):
    name, block, expect, why, opts = CASES[index]
    problems, detail = run_case(args, index)
    assert not problems, "%s: expected %s (%s)\n     %s" % (name, expect, why, "\n     ".join(problems))
    print("ok   %-55s %-8s %s" % (name, expect, detail))
