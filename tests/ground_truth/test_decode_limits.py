# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode refuses, up front and with little memory, input whose light field would be
absurd: microimages farther apart than the image is wide or high, or a light field over the
decoder's limit (4 GiB of float32, plenoptic_lf.LIGHT_FIELD_LIMIT_BYTES).

Cases, each run as a child process whose peak resident memory is read from os.wait4's rusage
(and whose address space is capped at 2 GiB, so that a decoder that tries anyway fails instead
of taking the machine's memory):

  - a render whose microimages are larger than the image: pitch 2 mm (d = 2 mm), pixels 0.01 mm,
    64 x 48 pixels (the lattice spacing, 2 mm * (D + d) / D / 0.01 mm = 207.8 px, computed here
    from the thin-lens equation): exit 2, one line naming the field microimage_lattice.basis_px,
    the spacing and the image size;
  - hand-edited metadata of a normal render: the lattice basis (and disc diameter) scaled by 1000;
  - a normal render with --step 0.001 (an angular grid of thousands of samples per axis) and with
    --angular 30001: refused naming the limit and the options that reduce it;
  - every refusal: no traceback, nothing written, peak memory under 300 MiB;
  - positive control: the normal render decodes in under 300 MiB, and plenoptic_lf.plan_decode
    predicts exactly the shape of the light field the command wrote.
"""

import json
import os
import resource
import shutil
import subprocess
import types

import pytest

import plenoptic_testing as pt

PEAK_LIMIT_MIB = 300
ADDRESS_SPACE_CAP = 2 * 1024 ** 3

SCENE_WIDE = """camera {
  plenoptic
  location <0, 0, -2>
  look_at <0, 0, 0>
  main_lens { thin_lens focal_length 50 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 2 focal_length 2 distance 2 }
  sensor { pixel_size 0.01 }
}
plane { -z, 0 pigment { rgb <0.8, 0.35, 0.05> } finish { emission 1 diffuse 0 ambient 0 } }
"""
F, FOCUS, PITCH, ARRAY_DISTANCE, PIXEL = 50.0, 2000.0, 2.0, 2.0, 0.01

SCENE_NORMAL = SCENE_WIDE.replace("pitch 2 focal_length 2 distance 2", "pitch 0.1 focal_length 0.4 distance 0.4")


def cap_address_space():
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE_CAP, ADDRESS_SPACE_CAP))


def run_measured(command, cwd):
    """Runs command; (exit status, stderr text, peak resident memory of that child in MiB)."""
    err_path = os.path.join(cwd, "limits_stderr.txt")
    with open(err_path, "w") as err:
        child = subprocess.Popen(command, cwd=cwd, stdout=subprocess.DEVNULL, stderr=err,
                                 preexec_fn=cap_address_space)
        _, status, usage = os.wait4(child.pid, 0)
        child.returncode = os.waitstatus_to_exitcode(status)
    with open(err_path, errors="replace") as err:
        text = err.read()
    return child.returncode, text, usage.ru_maxrss / 1024.0  # Linux: kilobytes


@pytest.fixture(scope="module")
def renders(args):
    """The wide render, the normal one, the hand-edited metadata and the spacings they hold."""
    wide_png, _, _ = pt.render_ground_truth(args.povray, args.work, "limits_wide", SCENE_WIDE, 64, 48)
    png, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "limits_normal", SCENE_NORMAL, 96, 72)
    good = pt.read_json(meta_path)

    # The spacing the render's lattice must have, from the optics: the array at the main lens's
    # image distance D, each lens's centre projected from the main-lens centre onto the sensor.
    D = F * FOCUS / (FOCUS - F)
    spacing = PITCH * (D + ARRAY_DISTANCE) / D / PIXEL

    edited = os.path.join(args.work, "limits_edited.plenoptic.json")
    data = json.loads(json.dumps(good))
    lattice = data["microimage_lattice"]
    lattice["basis_px"] = [[x * 1000.0 for x in v] for v in lattice["basis_px"]]
    if lattice.get("microimage_diameter_px"):
        lattice["microimage_diameter_px"] *= 1000.0
    with open(edited, "w") as f:
        json.dump(data, f, indent=1)
    edited_spacing = (good["microimage_lattice"]["basis_px"][0][0] ** 2
                      + good["microimage_lattice"]["basis_px"][0][1] ** 2) ** 0.5 * 1000.0
    return types.SimpleNamespace(wide_png=wide_png, png=png, meta_path=meta_path, edited=edited,
                                 spacing=spacing, edited_spacing=edited_spacing)


# label, the decoder's arguments and the words of its one error line (functions of the renders).
CASES = [
    ("microimages larger than the image (render)", lambda r: [r.wide_png],
     lambda r: ["microimage_lattice.basis_px", "%.1f" % r.spacing, "64 x 48"]),
    ("hand-edited basis x 1000", lambda r: [r.png, r.edited],
     lambda r: ["microimage_lattice.basis_px", "%.1f" % r.edited_spacing, "96 x 72"]),
    ("--step 0.001", lambda r: [r.png, "--step", "0.001"], lambda r: ["limit", "4 GiB", "--step", "--angular"]),
    ("--angular 30001", lambda r: [r.png, "--angular", "30001"], lambda r: ["limit", "4 GiB", "--step", "--angular"]),
]


@pytest.mark.parametrize("label, arguments, words", CASES, ids=[c[0] for c in CASES])
def test_refused_up_front(args, renders, label, arguments, words):
    arguments, words = arguments(renders), words(renders)
    out = os.path.join(args.work, "limits_out_" + "".join(c if c.isalnum() else "_" for c in label))
    shutil.rmtree(out, ignore_errors=True)
    status, stderr, peak = run_measured(pt.decoder(args.tools) + arguments + ["-o", out, "-q"], args.work)
    lines = [l for l in stderr.splitlines() if l.strip()]
    assert (status == 2 and len(lines) == 1 and lines[0].startswith("plenoptic-decode: error:")
            and all(w in lines[0] for w in words) and "Traceback" not in stderr
            and not os.path.exists(os.path.join(out, "contact_sheet.png"))), (
        "%s: exit %d (want 2), stderr %r (want one line with %s)" % (label, status, stderr.strip()[-600:], words))
    assert peak < PEAK_LIMIT_MIB, "%s: peak memory %.0f MiB (want < %d)" % (label, peak, PEAK_LIMIT_MIB)


def test_normal_render_decodes_as_planned(args, renders):
    """Positive control, and the up-front size is the size of what gets built."""
    out = os.path.join(args.work, "limits_normal.lightfield")
    shutil.rmtree(out, ignore_errors=True)
    status, stderr, peak = run_measured(pt.decoder(args.tools) + [renders.png, "-o", out, "-q", "--no-gif"], args.work)
    assert (status == 0 and peak < PEAK_LIMIT_MIB), ("the normal render decodes: exit %d, peak memory %.0f MiB (want 0, < %d)%s"
                                                     % (status, peak, PEAK_LIMIT_MIB, "; stderr %r" % stderr[-400:] if status else ""))
    import plenoptic_lf
    plan = getattr(plenoptic_lf, "plan_decode", None)
    written = json.load(open(os.path.join(out, "lightfield.json")))["shape"]
    predicted = list(plan(plenoptic_lf.load_metadata(renders.meta_path)).shape) if plan else None
    assert (predicted == written), ("plan_decode predicts the light field's shape %s = written %s"
                                    % (predicted, written))
