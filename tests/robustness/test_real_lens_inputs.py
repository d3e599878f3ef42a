# SPDX-License-Identifier: AGPL-3.0-or-later
"""Real-lens inputs as users and tools produce them (docs/real-lenses.md, "Syntax", "Refusals",
"Setup of a long lens"):

- a lens file saved with a UTF-8 byte-order mark renders as the same file without it;
- an empty lens file, one of comments only, a lens_file naming a directory or "" are refused
  with what is wrong (not "a prescription needs at least one surface"), at the lens_file line;
- a radius beyond +-1e12 mm written inline is a flat surface: the lens renders as with radius 0
  (it used to block every ray: a black image);
- blade_rotation 1e300 is reduced modulo 360 / blades;
- a lens of 2,001 surfaces prints its setup's progress on stderr, and SIGINT during the setup
  stops the program promptly (the setup takes tens of seconds on this machine; unstoppable
  before, it ran to its end first).
"""
import os
import signal
import subprocess
import threading
import time

import numpy as np

import plenoptic_testing as pt

HEADER = "#version 3.7;\nglobal_settings { assumed_gamma 1 }\nbackground { rgb 1 }\n"
SINGLET = "0 10 0 10\n100 5 1.5 40\n-100 49 1 40\n"


def scene(main, array=""):
    return (HEADER + "camera {\n  plenoptic\n  location <0, 0, -3>\n  look_at <0, 0, 0>\n" + main + "\n" + array +
            "  sensor { pixel_size 0.01 }\n  samples 4\n}\n")


def workdir(args, name):
    work = os.path.join(args.work, name)
    os.makedirs(work, exist_ok=True)
    for entry in os.listdir(work):
        path = os.path.join(work, entry)
        if os.path.isfile(path):
            os.remove(path)
    return work


def render(args, work, name, text, size=(48, 36)):
    pt.write_text(os.path.join(work, name + ".pov"), text)
    out = os.path.join(work, name + ".png")
    run = pt.run_povray(args.povray, name + ".pov", out, size[0], size[1], ["+FN16", "File_Gamma=1.0", "-A"],
                        timeout=120, cwd=work)
    return run, out


def refused_at(args, work, name, main, line_text, fragments):
    text = scene(main)
    run, out = render(args, work, name, text)
    problems, err = pt.refusal_problems(run)
    assert not problems, "%s: %s\n%s" % (name, problems, pt.tail(run.output))
    efile, eline, message = err
    lines = text.splitlines()
    assert os.path.basename(efile) == name + ".pov" and line_text in lines[eline - 1], (err, lines[eline - 1])
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    assert not os.path.exists(out), "an image was written"
    print("ok   %-28s line %d: %s" % (name, eline, message[:150]))


def test_byte_order_mark_is_skipped(args):
    work = workdir(args, "bom")
    pt.write_text(os.path.join(work, "plain.dat"), SINGLET)
    with open(os.path.join(work, "bom.dat"), "wb") as f:
        f.write(b"\xef\xbb\xbf" + SINGLET.encode())
    images = []
    for name in ("plain", "bom"):
        run, out = render(args, work, name, scene('  main_lens { lens_file "%s.dat" focus_distance 3 }' % name))
        assert run.returncode == 0, "%s refused:\n%s" % (name, pt.tail(run.output))
        images.append(pt.read_pixels(out))
    assert images[0].mean() > 0.3, "the singlet renders a white world dark: %g" % images[0].mean()
    assert np.array_equal(images[0], images[1]), "the file with a byte-order mark renders differently"


def test_empty_files_directories_and_empty_names_are_named(args):
    work = workdir(args, "empty")
    pt.write_text(os.path.join(work, "empty.dat"), "")
    pt.write_text(os.path.join(work, "comments.dat"), "# radius thickness ior aperture\n\n")
    os.makedirs(os.path.join(work, "lensdir"), exist_ok=True)
    cases = [
        ("empty", "empty.dat", ['lens_file "empty.dat"', "the lens file is empty (0 bytes)", "one row per surface"]),
        ("comments", "comments.dat", ['lens_file "comments.dat"', "no surface row (only comments and blank lines)"]),
        ("directory", "lensdir", ['lens_file "lensdir"', "names a directory", "not a lens file"]),
        ("noname", "", ['lens_file ""', "names no file"]),
    ]
    for name, file, fragments in cases:
        refused_at(args, work, name, '  main_lens {\n    lens_file "%s"\n    focus_distance 3\n  }' % file,
                   'lens_file "%s"' % file, fragments)


def test_a_radius_beyond_the_bound_is_flat(args):
    work = workdir(args, "flat")
    images = []
    for name, rear in (("flat", "0"), ("huge", "1e20"), ("huger", "-1e200")):
        main = ("  main_lens {\n    prescription {\n      stop { thickness 10 aperture 10 }\n"
                "      surface { radius 100 thickness 5 ior 1.5 aperture 40 }\n"
                "      surface { radius %s thickness 0 ior 1 aperture 40 }\n    }\n    focus_distance 3\n  }" % rear)
        run, out = render(args, work, name, scene(main))
        assert run.returncode == 0, "%s refused:\n%s" % (name, pt.tail(run.output))
        images.append(pt.read_pixels(out))
    assert images[0].mean() > 0.3, images[0].mean()
    for name, image in zip(("huge", "huger"), images[1:]):
        assert np.array_equal(images[0], image), "radius %s does not render as a flat surface (mean %g against %g)" % (
            name, image.mean(), images[0].mean())


def test_blade_rotation_is_reduced_by_the_iris_symmetry(args):
    """blade_rotation 1e300 on a hexagonal iris is 1e300 mod 60 degrees (exact integer arithmetic
    here): the same image, and the metadata holds the reduced angle. (Unreduced, the angle
    swamped the 60 degrees between the blades: one blade, a half-plane iris, a brighter image.)"""
    work = workdir(args, "blades")
    reduced = int(1e300) % 60
    images = []
    for name, angle in (("reduced", "%d" % reduced), ("huge", "1e300")):
        main = '  main_lens { lens_file "singlet.dat" blades 6 blade_rotation %s focus_distance 3 }' % angle
        pt.write_text(os.path.join(work, "singlet.dat"), SINGLET)
        run, out = render(args, work, name, scene(main))
        assert run.returncode == 0, "%s refused:\n%s" % (name, pt.tail(run.output))
        assert pt.metadata_of(out)["main_lens"]["prescription"]["blade_rotation_deg"] == reduced, name
        images.append(pt.read_pixels(out))
    assert images[0].mean() > 0.3, images[0].mean()
    assert np.array_equal(images[0], images[1]), "means %g and %g" % (images[0].mean(), images[1].mean())


def long_lens(path, elements=1000):
    """A stop and 1,000 weak biconvex elements (R = +-1e5 mm, f about 1e5 mm each): 2,001 rows, a
    lens of about 100 mm focal length."""
    rows = ["0 0.1 0 8"]
    for _ in range(elements):
        rows += ["100000 0.1 1.5 20", "-100000 0.1 1 20"]
    pt.write_text(path, "\n".join(rows) + "\n")


def test_long_lens_setup_reports_progress_and_stops_on_sigint(args):
    work = workdir(args, "long")
    long_lens(os.path.join(work, "long.dat"))
    pt.write_text(os.path.join(work, "long.pov"), scene('  main_lens { lens_file "long.dat" focus_distance 5 }'))
    png = os.path.join(work, "long.png")
    proc = subprocess.Popen([args.povray, "+Ilong.pov", "+O" + png, "+W32", "+H24", "-D", "+WT2"], cwd=work,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
    lines = []
    seen = threading.Event()

    def read():
        for raw in proc.stderr:
            text = raw.decode("utf-8", "replace").rstrip()
            lines.append(text)
            if "setting up a lens of 2001 surfaces" in text:
                seen.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    started = time.time()
    while not seen.is_set() and proc.poll() is None and time.time() - started < 120:
        time.sleep(0.05)
    if not seen.is_set():
        proc.kill()
        proc.wait()
        raise AssertionError("no progress line for the setup of a 2,001-surface lens; stderr:\n" + "\n".join(lines[-15:]))
    time.sleep(1.0)  # into the setup
    assert proc.poll() is None, "the setup ended within a second: this test means nothing"
    sent = time.time()
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    took = time.time() - sent  # printed only
    reader.join(timeout=5)
    progress = [l for l in lines if "setting up a lens" in l]
    print("progress lines before SIGINT: %s; stopped %.2f s after it, exit %s" % (progress, took, proc.returncode))
    assert progress[0].startswith("plenoptic camera: setting up a lens of 2001 surfaces: pupil bounds 0 %"), progress
    # Promptly, without timing it: the program stops inside the setup, so no step it had left
    # reports 100 % (a program that finished the setup first and only then looked at the signal
    # would print the lit-area table's 100 % line: the setup reports every tenth of each step).
    assert not any(l.endswith("lit-area table 100 %") for l in progress), progress
    assert proc.returncode != 0
    assert not os.path.exists(png), "an image was written after SIGINT"
