# SPDX-License-Identifier: AGPL-3.0-or-later
"""The decoder reads the sensor's raw (docs/sensor.md, "Decoding raws").

plenoptic-decode takes <stem>.raw.png (DN, a Bayer mosaic or RGB) as well as the rendered
picture, and devignettes with the camera's white image (--white). Checked against answers that
are not the decoder's:
  - DN back to picture values, demosaiced: at every site its own colour equals the noise-free
    picture to the quantisation (a 16-bit read-out with 10^14 electrons a unit: shot noise 1e-7);
    the other colours equal it wherever the picture is flat over the site's 3 x 3 neighbourhood
    (bilinear interpolation is exact there);
  - devignetting: a grey world of radiance 0.5 rendered with irradiance radiometry, diffraction
    and an angular response (microimages falling off by 30 % and more) is 0.5 wherever the white
    image carries light, once divided by it;
  - the command line decodes a raw with --white and writes the light field.
"""
import os
import subprocess
import sys

import numpy as np

import plenoptic_testing as pt

W, H = 160, 120
CAMERA = """camera { plenoptic location <0, 0, -2.5> look_at <0, 0, 0>
  main_lens { thin_lens focal_length 50 f_number 2 focus_distance 2.5 }
  microlens_array { hexagonal pitch 0.014 focal_length 0.028 distance 0.028 }
  sensor { pixel_size 0.0014 %s }
  samples 16 %s }
"""
LOSSLESS = "bayer %s bit_depth 16 full_well 1e14 exposure 1e14"


def read_picture(path, meta_path, white=False):
    from plenoptic_lf.metadata import load_metadata
    from plenoptic_lf.cli import read_picture as read
    from plenoptic_lf.progress import Progress
    meta = load_metadata(meta_path, (W, H))
    return read(path, meta, "auto", Progress(False), white=white)


def test_bayer_raw_demosaics_to_the_picture(args):
    for pattern in ("rggb", "gbrg"):
        name = "sensor_raw_" + pattern
        png = pt.render(args.povray, args.work, name, pt.QUADRANT_CHART + CAMERA % (LOSSLESS % pattern, ""), W, H)
        raw = os.path.splitext(png)[0] + ".raw.png"
        truth = pt.read_linear(png)
        got = read_picture(raw, os.path.splitext(png)[0] + ".plenoptic.json")
        assert got.shape == truth.shape
        # The site's own colour: the picture to the 16-bit step (DN = round(65535 v)).
        cell = {"rggb": "RGGB", "gbrg": "GBRG"}[pattern]
        rows, cols = np.mgrid[0:H, 0:W]
        own = np.zeros((H, W), int)
        for index, colour in enumerate(cell):
            own[(rows % 2 == index // 2) & (cols % 2 == index % 2)] = "RGB".index(colour)
        own_got = np.take_along_axis(got, own[..., None], axis=2)[..., 0]
        own_truth = np.take_along_axis(truth, own[..., None], axis=2)[..., 0]
        assert np.abs(own_got - own_truth).max() <= 1.5 / 65535, np.abs(own_got - own_truth).max()
        # The interpolated colours where the picture is flat over 3 x 3.
        from scipy import ndimage
        spread = ndimage.maximum_filter(truth, size=(3, 3, 1)) - ndimage.minimum_filter(truth, size=(3, 3, 1))
        flat = spread < 0.002
        flat[:1] = flat[-1:] = False
        flat[:, :1] = flat[:, -1:] = False
        error = np.abs(got - truth)[flat]
        print("%s: %d flat site colours, demosaic error max %.2g" % (pattern, flat.sum(), error.max()))
        assert flat.sum() > 0.05 * flat.size
        assert error.max() < 0.003, error.max()
        # Where the picture is not flat, bilinear interpolation is not exact: the test can tell.
        assert np.abs(got - truth)[~flat].max() > 0.01


def test_devignetting_with_the_white_image_gives_the_radiance(args):
    scene = "#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb 0.5 }\n" + \
        CAMERA % ("angular_response 32", "radiometry irradiance diffraction white_image")
    png = pt.render(args.povray, args.work, "devignette", scene, W, H)
    meta = os.path.splitext(png)[0] + ".plenoptic.json"
    white_png = os.path.splitext(png)[0] + ".white.png"
    picture = read_picture(png, meta)
    white = read_picture(white_png, meta, white=True)
    from plenoptic_lf.sensor import devignette
    flat = devignette(picture, white)
    # Lit: the white image above a tenth of its bright level (docs/sensor.md), channel by channel.
    lit = white > 0.1 * np.percentile(white, 99.9)
    print("devignette: raw %.3f..%.3f over the lit pixels, devignetted %.4f..%.4f"
          % (picture[lit].min(), picture[lit].max(), flat[lit].min(), flat[lit].max()))
    assert picture[lit].min() < 0.35  # the raw falls off within the microimages
    assert np.abs(flat[lit] - 0.5).max() < 0.002
    assert (flat[~lit] == 0).all()


def test_decode_command_reads_a_raw_with_a_white_image(args):
    scene = pt.TEXTURED_SCENE + CAMERA % (LOSSLESS % "grbg" + " angular_response 8",
                                          "radiometry irradiance diffraction white_image noise_free")
    png = pt.render(args.povray, args.work, "decode_raw", scene, W, H)
    stem = os.path.splitext(png)[0]
    out = os.path.join(args.work, "decode_raw.lightfield")
    run = subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-decode"), stem + ".raw.png",
                          "--white", stem + ".white.png", "-o", out, "--no-gif"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "demosaiced" in run.stderr and "devignetted" in run.stderr, run.stderr
    assert os.path.exists(os.path.join(out, "lightfield.npy"))
