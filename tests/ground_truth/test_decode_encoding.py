# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode honours the raw image's own encoding: the same scene written as a linear
16-bit PNG, an sRGB 16-bit PNG, an 8-bit PNG (sRGB and linear), a gamma-2.2 PNG and an EXR
decodes to the same linear light field.

Scene: a flat emissive plane (finish { emission 1 diffuse 0 }, pigment rgb C, assumed_gamma 1)
filling the view of a plenoptic 1.0 camera. Every fully lit pixel then holds exactly C in linear
light, whatever the camera does, so every lens of the decoded centre view must be C, up to the
file's quantisation: half a step of the stored integer, carried through the file's transfer
curve (written out again below, not taken from the decoder), or half a unit in the last place
of the EXR's 16-bit floats.

Checks:
  - what povray writes: the PNG chunks (read here byte by byte): +FN16 File_Gamma=1.0 has
    gAMA 100000 and no sRGB chunk; the default (File_Gamma sRGB) has an sRGB chunk (and gAMA
    45455); File_Gamma=2.2 has gAMA 45455 alone; and what OpenImageIO reports for each
    (oiio:ColorSpace, oiio:Gamma);
  - the decoder's default (--encoding auto) gives C for every file, so the central views agree
    with each other within the sum of their quantisation bounds;
  - it says which encoding it applied, and why, on stderr;
  - --encoding still overrides: the linear PNG read as sRGB gives srgb_to_linear(C), the sRGB PNG
    read as linear gives the sRGB-encoded C.
"""

import json
import os
import shutil
import struct
import subprocess

import numpy as np

import pytest

import plenoptic_testing as pt

W, H = 96, 72
C = (0.8, 0.35, 0.05)  # linear radiance of the plane; 0.05 is on the steep part of the sRGB curve

SCENE = """camera {
  plenoptic
  location <0, 0, -2>
  look_at <0, 0, 0>
  main_lens { thin_lens focal_length 50 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 }
  sensor { pixel_size 0.01 }
}
plane { -z, 0 pigment { rgb <%r, %r, %r> } finish { emission 1 diffuse 0 ambient 0 } }
""" % C

# name, output file, povray options, bits (0 = float), transfer curve of the stored values,
# and the OpenImageIO attributes and PNG chunks expected.
CASES = [
    ("linear16", "png", ["+FN16", "File_Gamma=1.0"], 16, "linear"),
    ("srgb16", "png", ["+FN16"], 16, "srgb"),
    ("srgb8", "png", ["+FN8"], 8, "srgb"),
    ("linear8", "png", ["+FN8", "File_Gamma=1.0"], 8, "linear"),
    ("gamma22_16", "png", ["+FN16", "File_Gamma=2.2"], 16, 2.2),
    ("exr", "exr", ["+FE"], 0, "linear"),
]


# The transfer curves, written out again (IEC 61966-2-1 for sRGB).
def encode(linear, curve):
    x = np.asarray(linear, dtype=np.float64)
    if curve == "linear":
        return x
    if curve == "srgb":
        return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.power(x, 1.0 / curve)


def decode_curve(stored, curve):
    y = np.asarray(stored, dtype=np.float64)
    if curve == "linear":
        return y
    if curve == "srgb":
        return np.where(y <= 0.04045, y / 12.92, np.power((y + 0.055) / 1.055, 2.4))
    return np.power(np.clip(y, 0, None), curve)


def quantisation_bound(value, bits, curve):
    """Largest linear error of storing `value` (per channel): half a step of a `bits`-bit integer
    through the curve, or half an ulp of a half float (relative 2**-11) for bits == 0."""
    value = np.asarray(value, dtype=np.float64)
    if bits == 0:
        return value * 2.0 ** -11 + 1e-7
    half_step = 0.5 / (2 ** bits - 1)
    e = encode(value, curve)
    return np.maximum(np.abs(decode_curve(e + half_step, curve) - value),
                      np.abs(decode_curve(np.clip(e - half_step, 0, None), curve) - value)) * 1.02 + 1e-7


def png_chunks(path):
    """{chunk type: [payloads]} of a PNG file, read byte by byte."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise AssertionError("%s is not a PNG file" % path)
    chunks, i = {}, 8
    while i + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[i:i + 8])
        chunks.setdefault(kind.decode("latin-1"), []).append(data[i + 8:i + 8 + length])
        i += 12 + length
    return chunks


def oiio_attributes(path):
    from plenoptic_lf.images import ImageFile
    with ImageFile(path) as image:
        spec = image.spec
    return spec.get_string_attribute("oiio:ColorSpace", ""), spec.get_float_attribute("oiio:Gamma", 0.0)


def render(args, name, ext, options):
    for stale in (name + "." + ext, name + ".plenoptic.json"):
        if os.path.exists(os.path.join(args.work, stale)):
            os.remove(os.path.join(args.work, stale))
    pt.write_text(os.path.join(args.work, "encoding.pov"), pt.SCENE_HEADER + SCENE)
    cmd = [args.povray, "+Iencoding.pov", "+O%s.%s" % (name, ext), "+W%d" % W, "+H%d" % H, "-D", "-P"] + options
    run = pt.run_process(cmd, cwd=args.work, timeout=300)
    assert run.returncode == 0, "rendering %s exited with status %d\n%s" % (name, run.returncode, run.output[-3000:])
    return os.path.join(args.work, name + "." + ext)


def decode(args, image, out, extra=()):
    """Runs plenoptic-decode; (exit status, stderr, centre view (T, S, 3) or None)."""
    shutil.rmtree(out, ignore_errors=True)
    run = subprocess.run(pt.decoder(args.tools) + [image, "-o", out,
                          "--no-gif"] + list(extra), capture_output=True, text=True)
    npy = os.path.join(out, "lightfield.npy")
    if run.returncode != 0 or not os.path.exists(npy):
        return run.returncode, run.stderr, None
    data = np.load(npy)
    description = json.load(open(os.path.join(out, "lightfield.json")))
    n_v, n_u = data.shape[2:4]
    if not description["usable_mask"][n_v // 2][n_u // 2]:
        raise AssertionError("the centre angular sample of %s is not usable" % image)
    return run.returncode, run.stderr, data[:, :, n_v // 2, n_u // 2, :].astype(np.float64)


@pytest.fixture(scope="module")
def files(args):
    """name -> the render of each case (what povray writes and OpenImageIO reports)."""
    out = {}
    for name, ext, options, bits, curve in CASES:
        out[name] = render(args, name, ext, options)
    for name, ext, options, bits, curve in CASES:
        print("      %-11s %s %-28s OpenImageIO: oiio:ColorSpace %r, oiio:Gamma %g"
              % (name, ext, " ".join(options), *oiio_attributes(out[name])))
    return out


# PNG chunks: File_Gamma=1.0 -> gAMA 100000 alone; default (sRGB) -> an sRGB chunk and gAMA 45455;
# File_Gamma=2.2 -> gAMA 45455 alone.
CHUNKS = [("linear16", "linear"), ("linear8", "linear"), ("srgb16", "srgb"), ("srgb8", "srgb"),
          ("gamma22_16", "gamma22")]


@pytest.mark.parametrize("name, kind", CHUNKS, ids=[c[0] for c in CHUNKS])
def test_png_gamma_chunks(files, name, kind):
    chunks = png_chunks(files[name])
    gama = [struct.unpack(">I", c)[0] for c in chunks.get("gAMA", [])]
    if kind == "linear":
        assert (gama == [100000] and "sRGB" not in chunks and "iCCP" not in chunks), (
            "%s (File_Gamma=1.0): gAMA %s, sRGB chunk %s, iCCP %s (want gAMA 100000 alone)"
            % (name, gama, "sRGB" in chunks, "iCCP" in chunks))
    elif kind == "srgb":
        assert ("sRGB" in chunks and gama == [45455]), (
            "%s (default File_Gamma, sRGB): sRGB chunk %s, gAMA %s (want an sRGB chunk and gAMA 45455)"
            % (name, "sRGB" in chunks, gama))
    else:
        assert (gama == [45455] and "sRGB" not in chunks), (
            "%s (File_Gamma=2.2): gAMA %s, sRGB chunk %s (want gAMA 45455 alone)" % (name, gama, "sRGB" in chunks))


@pytest.fixture(scope="module")
def decoded(args, files):
    """name -> (exit status, stderr, centre view) of plenoptic-decode with the default encoding."""
    return {name: decode(args, files[name], os.path.join(args.work, "encoding_%s.lightfield" % name))
            for name, ext, options, bits, curve in CASES}


@pytest.mark.parametrize("name, ext, options, bits, curve", CASES, ids=[c[0] for c in CASES])
def test_default_encoding(decoded, name, ext, options, bits, curve):
    """Decoded with the file's own encoding, the centre view is C everywhere."""
    expected = np.array(C)
    status, stderr, centre = decoded[name]
    assert status == 0 and centre is not None, ("%s: plenoptic-decode exits 0 (got %d%s)"
                                                % (name, status, "; stderr %r" % stderr[-400:] if status else ""))
    want_word = "encoding %s" % (curve if isinstance(curve, str) else "gamma %g" % curve)
    assert (want_word in stderr), ("%s: the decoder says which encoding it applied: %r in %r"
                                   % (name, want_word, [l for l in stderr.splitlines() if "encoding" in l]))
    bound = quantisation_bound(expected, bits, curve)
    error = np.abs(centre - expected).reshape(-1, 3).max(axis=0)
    assert (np.all(error <= bound)), (
        "%s (%s, %s %s): centre view of %d lenses = C within the quantisation bound: mean %s, "
        "worst error %s <= %s" % (name, ext, "%d-bit" % bits if bits else "half float", curve,
                                 centre.shape[0] * centre.shape[1],
                                 np.round(centre.reshape(-1, 3).mean(axis=0), 6), error, bound))


def test_central_views_agree(decoded):
    expected = np.array(C)
    centres = {}
    for name, ext, options, bits, curve in CASES:
        status, stderr, centre = decoded[name]
        if status == 0 and centre is not None:
            centres[name] = (centre, quantisation_bound(expected, bits, curve))
    names = sorted(centres)
    worst = []
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            if centres[a][0].shape != centres[b][0].shape:
                worst.append((a, b, "shapes differ"))
                continue
            difference = np.abs(centres[a][0] - centres[b][0]).reshape(-1, 3).max(axis=0)
            if np.any(difference > centres[a][1] + centres[b][1]):
                worst.append((a, b, difference))
    assert (len(names) == len(CASES) and not worst), (
        "the %d central views agree pairwise within the sum of their quantisation bounds%s"
        % (len(names), "; not: %s" % worst if worst else ""))


OVERRIDES = [("linear16", "srgb", 16, "linear"), ("srgb16", "linear", 16, "srgb")]


@pytest.mark.parametrize("name, option, bits, curve", OVERRIDES, ids=["%s-as-%s" % c[:2] for c in OVERRIDES])
def test_encoding_option_overrides_the_file(args, files, name, option, bits, curve):
    expected = np.array(C)
    want = decode_curve(expected, "srgb") if option == "srgb" else encode(expected, "srgb")
    status, stderr, centre = decode(args, files[name], os.path.join(args.work, "encoding_%s_as_%s.lightfield"
                                                                    % (name, option)), ["--encoding", option])
    assert status == 0 and centre is not None, ("%s --encoding %s: exit 0 (got %d%s)"
                                                % (name, option, status, "; stderr %r" % stderr[-400:] if status else ""))
    # The stored value's error, carried through the override's curve instead of the file's.
    bound = np.abs(decode_curve(encode(expected, curve) + 0.5 / 65535, option) - want) * 1.05 + 1e-6
    error = np.abs(centre - want).reshape(-1, 3).max(axis=0)
    assert (np.all(error <= bound)), ("%s --encoding %s overrides the file: centre %s, want %s (worst error %s <= %s)"
                                      % (name, option, np.round(centre.reshape(-1, 3).mean(axis=0), 6),
                                         np.round(want, 6), error, bound))
    assert ("encoding %s (--encoding)" % option in stderr), ("%s --encoding %s: the decoder says so: %r"
                                                             % (name, option, [l for l in stderr.splitlines() if "encoding" in l]))
