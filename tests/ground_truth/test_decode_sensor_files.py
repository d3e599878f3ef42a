# SPDX-License-Identifier: AGPL-3.0-or-later
"""The decoder knows the sensor's raw and the white images by their content, not only by their
names (docs/sensor.md, "Decoding raws"): data sets and calibration pipelines rename files.

The renderer writes the raw (and a white image in DN) as a 16-bit PNG holding the DN, with an
sBIT chunk equal to the read-out's bit depth, one channel for a Bayer mosaic, and no
colour-encoding chunk; a linear white image as a 16-bit PNG with sBIT 16. The test reads those
chunks itself (a few lines of struct, below) to check what the renders hold, then:
  - a raw copied under another name decodes to exactly the light field of the original (and
    with --raw too); a raw re-saved without its sBIT chunk is read as a picture with a warning
    naming --raw, and --raw then decodes it as the original;
  - a white image in DN under another name devignettes exactly as the original; a linear one
    is refused until --white-scale gives its scale, and then devignettes as the original; with a
    16-bit read-out, where DN and linear white images look alike, --white-values is asked for;
  - an 8-bit file, or the render's 16-bit RGB picture, under the raw's name is refused with
    the bit depth, channels and sBIT expected and found;
  - the options contradicting the content or the metadata are refused, each with its reason.
"""
import os
import shutil
import struct
import subprocess
import sys

import numpy as np

import plenoptic_testing as pt

W, H = 160, 120
CAMERA = """camera { plenoptic location <0, 0, -3> look_at <0, 0, 0>
  main_lens { thin_lens focal_length 50 f_number 2 focus_distance 3 }
  microlens_array { hexagonal pitch 0.014 focal_length 0.028 distance 0.028 }
  sensor { pixel_size 0.0014 angular_response 8 %s }
  radiometry irradiance
  samples 4 %s }
"""
READ_OUT_12 = "bayer rggb bit_depth 12 full_well 20000 black_level 64"
READ_OUT_16 = "bayer grbg bit_depth 16 full_well 1e6"

_renders = {}


def png_chunks(path):
    """IHDR's bit depth and colour type, the sBIT bytes (or None) and the chunk names before IDAT."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    at, names, sbit, ihdr = 8, [], None, None
    while True:
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        kind = kind.decode()
        if kind == "IDAT":
            return ihdr, sbit, names
        names.append(kind)
        if kind == "IHDR":
            ihdr = (body[8], body[9])
        elif kind == "sBIT":
            sbit = tuple(body)
        at += 12 + length


def rendered(args, name):
    """Renders (once per session) one of three cameras: 'dn12' (12-bit rggb read-out, white image
    in DN), 'linear' (no read-out, linear white image), 'dn16' (16-bit grbg read-out, white image
    in DN). Returns the stem of its files."""
    if name not in _renders:
        sensor, extra = {"dn12": (READ_OUT_12, "white_image"), "linear": ("", "white_image"),
                         "dn16": (READ_OUT_16, "white_image")}[name]
        png = pt.render(args.povray, args.work, "files_" + name, pt.TEXTURED_SCENE + CAMERA % (sensor, extra), W, H)
        _renders[name] = os.path.splitext(png)[0]
    return _renders[name]


def decode(args, raw, meta, out, *options):
    """plenoptic-decode RAW META -o OUT --no-gif OPTIONS: (exit status, stderr, L or None)."""
    run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-decode"), raw, meta, "-o", out,
                          "--no-gif"] + list(options), capture_output=True, text=True, timeout=300)
    path = os.path.join(out, "lightfield.npy")
    lf = np.load(path) if run.returncode == 0 and os.path.exists(path) else None
    if os.path.isdir(out):
        shutil.rmtree(out)
    return run.returncode, run.stderr, lf


def copy(src, work, name):
    dst = os.path.join(work, name)
    shutil.copyfile(src, dst)
    return dst


def centre_mean(lf):
    n = lf.shape[2]
    return float(lf[:, :, n // 2, n // 2].mean())


def test_the_renders_files_have_the_documented_layout(args):
    """What the rules below rest on: 16-bit, sBIT = the bit depth, one channel for a mosaic, no
    colour encoding (the picture itself has gAMA)."""
    dn12, linear, dn16 = rendered(args, "dn12"), rendered(args, "linear"), rendered(args, "dn16")
    for path, bits, colour_type in ((dn12 + ".raw.png", 12, 0), (dn12 + ".white.png", 12, 0),
                                    (dn16 + ".raw.png", 16, 0), (dn16 + ".white.png", 16, 0),
                                    (linear + ".white.png", 16, 0)):
        ihdr, sbit, names = png_chunks(path)
        assert ihdr == (16, colour_type) and sbit == (bits,), (path, ihdr, sbit)
        assert not {"gAMA", "sRGB", "iCCP"} & set(names), (path, names)
    ihdr, sbit, names = png_chunks(dn12 + ".png")
    assert ihdr == (16, 2) and "gAMA" in names, (ihdr, names)


def test_a_renamed_raw_decodes_as_the_original(args):
    stem = rendered(args, "dn12")
    meta = stem + ".plenoptic.json"
    status, err, original = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "orig"))
    assert status == 0, err
    renamed = copy(stem + ".raw.png", args.work, "frame_0001.png")
    status, err, got = decode(args, renamed, meta, os.path.join(args.work, "renamed"))
    assert status == 0, err
    print("centre view mean: original %.4f, renamed %.4f" % (centre_mean(original), centre_mean(got)))
    assert np.array_equal(got, original)
    assert "recognised by its content" in err and "demosaiced" in err, err
    status, err, told = decode(args, renamed, meta, os.path.join(args.work, "renamed_raw"), "--raw")
    assert status == 0, err
    assert np.array_equal(told, original)
    assert centre_mean(original) > 0.05  # a lit scene, not the DN / 65535 of a misread raw


def test_a_raw_resaved_without_sbit_needs_raw(args):
    """Another tool's 16-bit PNG of the same DN (no sBIT): a picture with a warning, --raw decodes it."""
    from PIL import Image
    stem = rendered(args, "dn12")
    meta = stem + ".plenoptic.json"
    dn = np.rint(pt.load(stem + ".raw.png")[..., 0] * 65535).astype(np.uint16)
    resaved = os.path.join(args.work, "resaved.png")
    Image.fromarray(dn).save(resaved)
    ihdr, sbit, names = png_chunks(resaved)
    assert ihdr == (16, 0) and sbit is None and "gAMA" not in names
    status, err, as_picture = decode(args, resaved, meta, os.path.join(args.work, "resaved"))
    assert status == 0, err
    assert "warning" in err and "--raw" in err, err
    status, err, told = decode(args, resaved, meta, os.path.join(args.work, "resaved_raw"), "--raw")
    assert status == 0, err
    status, err, original = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "orig2"))
    assert np.array_equal(told, original)
    assert not np.allclose(as_picture, original, atol=0.01)


def test_a_renamed_white_image_in_dn_devignettes_as_the_original(args):
    stem = rendered(args, "dn12")
    meta = stem + ".plenoptic.json"
    status, err, original = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "w_orig"),
                                   "--white", stem + ".white.png")
    assert status == 0, err
    white = copy(stem + ".white.png", args.work, "flat_field_A.png")
    status, err, got = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "w_renamed"), "--white", white)
    assert status == 0, err
    print("devignetted centre view mean: original %.4f, renamed %.4f" % (centre_mean(original), centre_mean(got)))
    assert np.array_equal(got, original)
    assert "white image in DN, recognised by its content" in err, err
    status, err, told = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "w_told"), "--white", white,
                               "--white-values", "dn")
    assert status == 0, err
    assert np.array_equal(told, original)
    # The same white image read as linear would not: the options must agree with the content.
    status, err, _ = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "w_wrong"), "--white", white,
                            "--white-values", "linear", "--white-scale", "1")
    assert status == 2 and "not a linear white image" in err and "sBIT 12" in err, err


def test_a_renamed_linear_white_image_needs_its_scale(args):
    stem = rendered(args, "linear")
    meta = stem + ".plenoptic.json"
    scale = pt.load_metadata(meta)["white_images"][0]["scale"]
    status, err, original = decode(args, stem + ".png", meta, os.path.join(args.work, "l_orig"),
                                   "--white", stem + ".white.png")
    assert status == 0, err
    white = copy(stem + ".white.png", args.work, "flat_field_B.png")
    status, err, _ = decode(args, stem + ".png", meta, os.path.join(args.work, "l_renamed"), "--white", white)
    assert status == 2 and "--white-scale" in err and "scale %g" % scale in err, err
    status, err, got = decode(args, stem + ".png", meta, os.path.join(args.work, "l_scaled"), "--white", white,
                              "--white-scale", "%r" % scale)
    assert status == 0, err
    assert np.array_equal(got, original)
    # Twice the scale halves the devignetted light field: the scale is what was asked for.
    status, err, doubled = decode(args, stem + ".png", meta, os.path.join(args.work, "l_doubled"), "--white", white,
                                  "--white-scale", "%r" % (2 * scale))
    assert status == 0, err
    assert np.allclose(doubled, original / 2, rtol=1e-5, atol=1e-7)
    # A scale contradicting the metadata's for the file it names is refused.
    status, err, _ = decode(args, stem + ".png", meta, os.path.join(args.work, "l_contra"),
                            "--white", stem + ".white.png", "--white-scale", "%r" % (2 * scale))
    assert status == 2 and "contradicts the metadata" in err, err


def test_dn_and_linear_white_images_alike_need_white_values(args):
    """With a 16-bit read-out a white image in DN has sBIT 16, as a linear one does."""
    stem = rendered(args, "dn16")
    meta = stem + ".plenoptic.json"
    status, err, original = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "a_orig"),
                                   "--white", stem + ".white.png")
    assert status == 0, err
    white = copy(stem + ".white.png", args.work, "flat_field_C.png")
    status, err, _ = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "a_renamed"), "--white", white)
    assert status == 2 and "--white-values" in err and "fits both" in err, err
    status, err, got = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "a_told"), "--white", white,
                              "--white-values", "dn")
    assert status == 0, err
    assert np.array_equal(got, original)


def test_files_under_the_raws_name_must_be_a_raw(args):
    stem = rendered(args, "dn12")
    meta = stem + ".plenoptic.json"
    folder = os.path.join(args.work, "impostors")
    os.makedirs(folder, exist_ok=True)
    raw_name = pt.load_metadata(meta)["sensor"]["read_out"]["raw_file"]
    # An 8-bit copy of the picture.
    eight = os.path.join(folder, raw_name)
    pt.save_png(eight, pt.read_linear(stem + ".png"))
    assert png_chunks(eight)[0] == (8, 2)
    status, err, _ = decode(args, eight, meta, os.path.join(args.work, "i_8"))
    print(err.strip().splitlines()[-1])
    assert status == 2 and "name of the sensor's raw" in err and "8-bit" in err and "16-bit" in err, err
    assert "sBIT 12" in err and "grey" in err, err
    # The render's own 16-bit picture: RGB, sBIT 16, gAMA.
    os.remove(eight)
    picture = copy(stem + ".png", folder, raw_name)
    status, err, _ = decode(args, picture, meta, os.path.join(args.work, "i_16"))
    assert status == 2 and "16-bit RGB PNG, sBIT 16, colour encoding in gAMA" in err, err
    # --raw on the picture under its own name: the same refusal.
    status, err, _ = decode(args, stem + ".png", meta, os.path.join(args.work, "i_raw"), "--raw")
    assert status == 2 and "--raw: " in err and "not the sensor's raw in DN" in err, err
    # A 16-bit grey file without sBIT whose values exceed 12 bits.
    os.remove(picture)
    from PIL import Image
    wide = os.path.join(folder, raw_name)
    Image.fromarray(np.full((H, W), 5000, np.uint16)).save(wide)
    status, err, _ = decode(args, wide, meta, os.path.join(args.work, "i_wide"))
    assert status == 2 and "above 4095" in err, err


def test_options_that_contradict_are_refused(args):
    dn12 = rendered(args, "dn12")
    meta = dn12 + ".plenoptic.json"
    out = os.path.join(args.work, "contra")
    cases = [
        # (raw, metadata, options, words of the message)
        (dn12 + ".raw.png", meta, ["--raw", "--encoding", "linear"], ["--encoding applies to a rendered picture"]),
        (copy(dn12 + ".raw.png", args.work, "frame_0002.png"), meta, ["--encoding", "srgb"],
         ["--encoding applies to a rendered picture", "recognised by its content"]),
        (dn12 + ".raw.png", meta, ["--white", dn12 + ".white.png", "--white-values", "linear"],
         ["contradicts the metadata", "is dn"]),
        (dn12 + ".raw.png", meta, ["--white", dn12 + ".white.png", "--white-scale", "2"],
         ["contradicts the metadata"]),
        (dn12 + ".raw.png", meta, ["--white-values", "dn"], ["need --white"]),
        (dn12 + ".raw.png", meta, ["--white", dn12 + ".png"], ["not a white image the renderer writes", "gAMA"]),
    ]
    linear = rendered(args, "linear")
    cases.append((linear + ".png", linear + ".plenoptic.json", ["--raw"], ["no read-out"]))
    for raw, meta_path, options, words in cases:
        status, err, _ = decode(args, raw, meta_path, out, *options)
        assert status == 2 and all(w in err for w in words), (options, err)
        assert [line for line in err.splitlines() if "error" in line] == [err.strip().splitlines()[-1]], err
        assert not os.path.exists(out)


def test_the_raw_is_refused_as_a_white_image(args):
    """A raw has a white image in DN's layout, so by content alone it would pass as one; the picture
    divided by its own raw decodes to about 1 everywhere. --white naming the input or the metadata's
    raw (sensor.read_out.raw_file; real paths compared: a symbolic link too) is refused."""
    stem = rendered(args, "dn12")
    meta = stem + ".plenoptic.json"
    link = os.path.join(args.work, "white_link.png")
    if os.path.lexists(link):
        os.remove(link)
    os.symlink(stem + ".raw.png", link)
    cases = [
        (stem + ".png", stem + ".raw.png", ["is the sensor's raw", "sensor.read_out.raw_file"]),
        (stem + ".png", link, ["is the sensor's raw", "sensor.read_out.raw_file"]),
        (stem + ".raw.png", stem + ".raw.png", ["is the input itself"]),
        (copy(stem + ".raw.png", args.work, "frame_0003.png"), os.path.join(args.work, "frame_0003.png"),
         ["is the input itself"]),
    ]
    out = os.path.join(args.work, "self_white")
    for raw, white, words in cases:
        status, err, lf = decode(args, raw, meta, out, "--white", white)
        if lf is not None:
            print("%s --white %s decoded: centre view mean %.4f" % (raw, white, centre_mean(lf)))
        assert status == 2 and all(w in err for w in words), (raw, white, status, err)
        assert len(err.strip().splitlines()) == 1, err
        assert not os.path.exists(out)
    # The camera's own white image still devignettes.
    status, err, _ = decode(args, stem + ".raw.png", meta, out, "--white", stem + ".white.png")
    assert status == 0, err


def test_the_first_line_says_what_the_input_is_read_as(args):
    """The raw in DN is not read in a colour encoding: the decoder's line about the input says what it is
    read as and claims no encoding; a picture's line names its encoding."""
    stem = rendered(args, "dn12")
    meta = stem + ".plenoptic.json"
    status, err, _ = decode(args, stem + ".raw.png", meta, os.path.join(args.work, "first_raw"))
    assert status == 0, err
    first = err.splitlines()[0]
    print(first)
    assert "read as the sensor's raw in DN" in first and "colour encoding is not used" in first, first
    assert "encoding srgb" not in err and "encoding linear" not in err and "the file's own" not in err, err
    renamed = copy(stem + ".raw.png", args.work, "frame_0004.png")
    status, err, _ = decode(args, renamed, meta, os.path.join(args.work, "first_renamed"))
    assert status == 0, err
    assert "read as the sensor's raw in DN, recognised by its content" in err.splitlines()[0], err
    assert "the file's own" not in err, err
    status, err, _ = decode(args, stem + ".png", meta, os.path.join(args.work, "first_picture"))
    assert status == 0, err
    first = err.splitlines()[0]
    print(first)
    assert "16-bit integer, encoding " in first and "read as" not in first, first
