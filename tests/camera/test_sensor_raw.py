# SPDX-License-Identifier: AGPL-3.0-or-later
"""The sensor's read-out (docs/sensor.md): `sensor { bayer ... }` writes <image>.raw.png
beside the noise-free picture.

The camera is a pinhole main lens without an array in front of a uniform background, so every
pixel's noise-free value is the background's colour exactly; what the raw holds is then the
chain's own statistics, checked against answers computed here:
- Bayer sites: in a pure red, green or blue world only the sites of that colour collect
  electrons, every other site reads the black level exactly (no read noise, no dark current);
- the photon-transfer curve: the variance of the DN over the picture against their mean, over
  exposures, is a line of slope g = (2^B - 1 - K) / E (Poisson shot noise), its foot in the dark
  is g^2 r^2 + 1/12 (read noise and rounding), and past the full well every site reads 2^B - 1;
- the raw depends on the seed and the picture only: +WT1 and +WT2 give the same bytes, another
  seed another raw; the picture itself is the same with or without a read-out.
"""
import os

import numpy as np
import pytest

import plenoptic_testing as pt

W, H = 96, 64


def scene(colour, sensor_body):
    return ("#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\nbackground { rgb <%r, %r, %r> }\n"
            "camera { plenoptic location <0, 0, -2> look_at <0, 0, 0>\n"
            "  main_lens { pinhole distance 10 }\n"
            "  sensor { pixel_size 0.01 %s }\n}\n" % (colour + (sensor_body,)))


def render_raw(args, name, colour, sensor_body, extra=()):
    path = pt.render(args.povray, args.work, name, scene(colour, sensor_body), W, H, extra=extra)
    raw_path = os.path.splitext(path)[0] + ".raw.png"
    assert os.path.exists(raw_path), "no raw beside %s" % path
    dn = np.rint(pt.load(raw_path) * 65535).astype(np.int64)
    return path, raw_path, dn


@pytest.mark.parametrize("pattern", ["rggb", "bggr", "grbg", "gbrg"])
def test_bayer_sites_of_pure_colours(args, pattern):
    black = 100
    for channel, colour in enumerate([(0.5, 0.0, 0.0), (0.0, 0.5, 0.0), (0.0, 0.0, 0.5)]):
        name = "bayer_%s_%d" % (pattern, channel)
        path, _, dn = render_raw(args, name, colour,
                                 "bayer %s bit_depth 12 full_well 4000 black_level %d" % (pattern, black))
        assert dn.shape[:2] == (H, W) and (dn.ndim == 2 or dn.shape[2] == 1), dn.shape
        dn = dn.reshape(H, W)
        # The site of pixel (i, j) (column i, row j from the top) records the colour named by
        # letter (j % 2) * 2 + (i % 2) of the pattern.
        rows, cols = np.mgrid[0:H, 0:W]
        letters = np.array(list(pattern))[(rows % 2) * 2 + (cols % 2)]
        mine = letters == "rgb"[channel]
        assert np.all(dn[~mine] == black), (pattern, channel, np.unique(dn[~mine]))
        # 0.5 of a 4000-electron exposure: 2000 electrons, (4095 - 100) / 4000 DN each.
        expected = black + 2000 * (4095 - black) / 4000.0
        lit = dn[mine]
        assert abs(lit.mean() - expected) < 5 * np.sqrt(2000.0 / lit.size) * (3995 / 4000.0) + 0.5, (lit.mean(), expected)
        meta = pt.metadata_of(path)["sensor"]["read_out"]
        assert meta["bayer"] == pattern and meta["raw_file"] == name + ".raw.png" and meta["black_level_dn"] == black


def test_photon_transfer_curve(args):
    bits, full_well, read_noise, black = 12, 20000.0, 6.0, 64
    g = (2 ** bits - 1 - black) / full_well
    means, variances = [], []
    for k, exposure in enumerate([500, 2000, 5000, 9000, 14000]):
        _, _, dn = render_raw(args, "ptc_%d" % k, (1.0, 1.0, 1.0),
                              "bit_depth %d full_well %r exposure %r read_noise %r black_level %d seed %d"
                              % (bits, full_well, exposure, read_noise, black, k))
        values = dn.astype(np.float64).ravel()  # every channel of every pixel: independent sites
        means.append(values.mean() - black)
        variances.append(values.var(ddof=1))
        assert abs(means[-1] - g * exposure) < 0.01 * g * exposure + 0.5, (exposure, means[-1], g * exposure)
    slope, intercept = np.polyfit(means, variances, 1)
    print("photon transfer: slope %.5f (gain %.5f DN/e), intercept %.2f" % (slope, g, intercept))
    # 18 432 sites a point: each variance is good to about 1 %.
    assert slope == pytest.approx(g, rel=0.03), (slope, g)
    _, _, dark = render_raw(args, "ptc_dark", (0.0, 0.0, 0.0),
                            "bit_depth %d full_well %r read_noise %r black_level %d" % (bits, full_well, read_noise, black))
    dark = dark.astype(np.float64).ravel()
    assert abs(dark.mean() - black) < 0.05, dark.mean()
    assert dark.var(ddof=1) == pytest.approx(g * g * read_noise ** 2 + 1 / 12.0, rel=0.05), dark.var(ddof=1)
    _, _, clipped = render_raw(args, "ptc_clipped", (1.0, 1.0, 1.0),
                               "bit_depth %d full_well %r exposure %r read_noise %r black_level %d"
                               % (bits, full_well, 2 * full_well, read_noise, black))
    assert np.all(clipped == 2 ** bits - 1), np.unique(clipped)


def test_raw_is_a_function_of_seed_and_picture(args):
    body = "bayer grbg bit_depth 10 full_well 3000 read_noise 4 dark_current 20 exposure_time 0.5 prnu 0.01 dsnu 2 seed 7"
    colour = (0.3, 0.6, 0.2)
    path1, raw1, dn1 = render_raw(args, "seed_wt1", colour, body, extra=["+WT1"])
    path2, raw2, dn2 = render_raw(args, "seed_wt2", colour, body, extra=["+WT2"])
    with open(raw1, "rb") as a, open(raw2, "rb") as b:
        assert a.read() == b.read(), "the raw depends on the thread count"
    _, _, dn3 = render_raw(args, "seed_other", colour, body.replace("seed 7", "seed 8"))
    assert np.mean(dn3 != dn1) > 0.5
    # The picture is the noise-free one, with or without a read-out.
    plain = pt.render(args.povray, args.work, "seed_plain", scene(colour, ""), W, H)
    assert np.array_equal(pt.load(plain), pt.load(path1))
    assert pt.metadata_of(plain)["sensor"]["read_out"] is None
    meta = pt.metadata_of(path1)["sensor"]["read_out"]
    assert meta["seed"] == 7 and meta["bit_depth"] == 10 and meta["exposure_e"] == 3000
    assert meta["gain_dn_per_e"] == pytest.approx(1023 / 3000.0)
