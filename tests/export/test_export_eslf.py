# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-export RENDER --to eslf DIR against LFToolbox's ESLF layout and our decoder
(docs/export/eslf.md).

Scene: a plenoptic 1.0 camera (F = 50 mm f/2 focused at 1 m, microlenses at d = f) looks at a
textured, self-lit plane at 0.7 m, through a rectangular array and through a hexagonal array
turned 3 degrees about the axis. For each:

- the ESLF is read back by a reader written here from LFToolbox's documentation of the format
  (LFReadESLF: the lenslet size from <file>.json's DecodeOptions.LFSize, the image cut into tiles
  of that size, a tile per lenslet, tiles in lenslet order; the alpha channel a weight): every
  tile equals the decoder's light field (plenoptic_lf.decode, run here on the same render) after
  the documented quantisation round(clip(L, 0, 1) x 65535), exactly; the weight is 65535 exactly
  on the usable microimage disc;
- the json's lenslet size is the angular grid the metadata implies (the usable disc: the smaller
  of the microimage diameter's half and half the lens spacing, less a pixel), and its microimage
  pitch is the thin-lens answer pitch (D + d) / D / pixel, worked out here;
- hexagonal: LFToolbox's LensletGridModel in the json, expanded here into its grid as
  LFToolbox's LFBuildHexGrid describes it (rows VSpacing apart, every other row from
  FirstPosShiftRow shifted by HSpacing / 2, turned by Rot about the offset, 1-based pixels), puts
  every grid point in the image on a microimage centre of the metadata within 1e-6 px and
  covers them; rectangular: the model is null, and the json says why;
- a scale that would clip is refused, and the folder is left untouched.
"""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import plenoptic_testing as pt

W, H = 300, 220
F, N_MAIN, FOCUS_M = 50.0, 2.0, 1.0
PITCH, MICRO_F, PIXEL = 0.07, 0.14, 0.01
Z_PLANE = 0.7

SCENE = """#declare Tex = texture {
  pigment { bozo color_map { [0 rgb <0.05, 0.1, 0.4>] [0.5 rgb <0.9, 0.9, 0.6>] [1 rgb <0.6, 0.1, 0.05>] } }
  finish { emission 1 diffuse 0 ambient 0 } }
camera {
  plenoptic
  location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }
  microlens_array { %%s pitch %r focal_length %r distance %r %%s }
  sensor { pixel_size %r }
  samples 4
}
plane { z, %r texture { Tex scale 0.01 } }
""" % (F, N_MAIN, FOCUS_M, PITCH, MICRO_F, MICRO_F, PIXEL, Z_PLANE)

CASES = {"rect": ("rectangular", ""), "hex": ("hexagonal", "rotate <0, 0, 3>")}


def run_export(args, *argv):
    return subprocess.run([sys.executable, os.path.join(args.tools, "plenoptic-export"), *argv],
                          capture_output=True, text=True, timeout=300)


def read_eslf(path):
    """LFToolbox's reading of an ESLF, written from its documentation: the json beside the file
    (<file>.json) gives the lenslet size (DecodeOptions.LFSize, first two entries); the image is
    cut into tiles of that size, one per lenslet, in lenslet order. Returns (LF[j, i, l, k, c]
    with j, i the sample in the tile (row, column) and l, k the tile's row and column, as uint16,
    the json)."""
    import OpenImageIO as oiio
    with open(path + ".json", encoding="utf-8") as f:
        doc = json.load(f)
    tile_rows, tile_cols = doc["DecodeOptions"]["LFSize"][:2]
    # PNG stores colour unassociated with alpha, as LFToolbox's imread returns it; OpenImageIO
    # would multiply it by alpha unless told not to.
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)
    image = oiio.ImageInput.open(path, config)
    assert image is not None, oiio.geterror()
    spec = image.spec()
    assert spec.format == oiio.UINT16, "%s: 16-bit samples, found %s" % (path, spec.format)
    pixels = image.read_image(oiio.UINT16)
    image.close()
    height, width, channels = pixels.shape
    assert height % tile_rows == 0 and width % tile_cols == 0, "the image is a whole number of tiles"
    lf = pixels.reshape(height // tile_rows, tile_rows, width // tile_cols, tile_cols, channels)
    return lf.transpose(1, 3, 0, 2, 4), doc


def lfbuild_hex_grid(model):
    """LFToolbox's LFBuildHexGrid, from its documentation: grid (row, column) at
    (column HSpacing [+ HSpacing / 2 on rows FirstPosShiftRow, +2, ...], row VSpacing), turned by
    Rot and moved to (HOffset, VOffset); 1-based pixel coordinates. Returns (VMax, UMax, 2), x y."""
    rows, cols = np.mgrid[0:model["VMax"], 0:model["UMax"]].astype(float)
    u = cols * model["HSpacing"]
    v = rows * model["VSpacing"]
    shifted = (np.arange(model["VMax"]) + 1 - model["FirstPosShiftRow"]) % 2 == 0
    u[shifted & (np.arange(model["VMax"]) + 1 >= model["FirstPosShiftRow"])] += 0.5 * model["HSpacing"]
    c, s = math.cos(model["Rot"]), math.sin(model["Rot"])
    return np.stack([c * u - s * v + model["HOffset"], s * u + c * v + model["VOffset"]], axis=-1)


def expected_angular_count(meta_doc):
    """Samples per axis of the usable microimage disc at 1 px steps, from the metadata: the disc's
    radius is the smaller of half the microimage diameter and half the nearest centre spacing, less
    one pixel."""
    lattice = meta_doc["microimage_lattice"]
    a, b = (np.array(v, float) for v in lattice["basis_px"])
    spacing = min(np.hypot(*a), np.hypot(*b)) if meta_doc["microlens_array"]["grid"] == "rectangular" else np.hypot(*a)
    radius = min(0.5 * spacing, 0.5 * lattice["microimage_diameter_px"]) - 1.0
    return 2 * int(math.floor(radius + 1e-9)) + 1


@pytest.fixture(scope="module")
def exports(args):
    out = {}
    for name, (grid, rotate) in CASES.items():
        png, meta, _ = pt.render_ground_truth(args.povray, args.work, "eslf_" + name, SCENE % (grid, rotate), W, H)
        folder = os.path.join(args.work, "eslf_" + name + "_out")
        run = run_export(args, png, "--to", "eslf", folder, "-q")
        assert run.returncode == 0, "plenoptic-export --to eslf exits 0 (%s): %s" % (name, run.stderr[-2000:])
        out[name] = (png, meta, folder, run.stdout.split())
    return out


@pytest.mark.parametrize("name", sorted(CASES))
def test_tiles_are_the_decoders_views(args, exports, name):
    import plenoptic_lf as plf
    png, meta_path, folder, listed = exports[name]
    eslf = os.path.join(folder, "eslf_%s.eslf.png" % name)
    assert sorted(listed) == sorted([eslf, eslf + ".json"]), listed
    lf_file, doc = read_eslf(eslf)
    raw = plf.read_raw(png)
    meta = plf.load_metadata(meta_path, (raw.shape[1], raw.shape[0]))
    lf = plf.decode(raw, meta)
    T, S, n_v, n_u, _ = lf.data.shape
    assert lf_file.shape == (n_v, n_u, T, S, 4), "tiles %s, decoder %s" % (lf_file.shape, lf.data.shape)
    assert doc["plenoptic"]["scale"] == 1.0
    expected = np.floor(np.clip(lf.data.astype(np.float64), 0, 1) * 65535 + 0.5).astype(np.uint16)
    got = lf_file[..., :3].transpose(2, 3, 0, 1, 4)  # -> [t, s, v, u, c]
    differ = int(np.count_nonzero(got != expected))
    assert differ == 0, "%d of %d samples differ from the decoder's (largest %d)" % (
        differ, got.size, int(np.abs(got.astype(int) - expected).max()))
    weight = lf_file[..., 3].transpose(2, 3, 0, 1)
    assert np.array_equal(weight, np.where(lf.mask[None, None] & ~lf.dark[:, :, None, None], 65535, 0)), \
        "the weight is 65535 exactly on the usable disc"
    assert 0.05 < expected.mean() / 65535 < 0.95, "the tiles carry the scene, not black or white"


@pytest.mark.parametrize("name", sorted(CASES))
def test_json_lenslet_size_and_pitch(args, exports, name):
    png, meta_path, folder, _ = exports[name]
    with open(os.path.join(folder, "eslf_%s.eslf.png.json" % name), encoding="utf-8") as f:
        doc = json.load(f)
    with open(meta_path, encoding="utf-8") as f:
        meta_doc = json.load(f)
    n = expected_angular_count(meta_doc)
    assert doc["DecodeOptions"]["LFSize"][:2] == [n, n] and doc["plenoptic"]["lenslet_size_px"] == [n, n], \
        "lenslet size %s, the metadata's usable disc gives %d" % (doc["DecodeOptions"]["LFSize"], n)
    D = pt.thin_lens_D(F, FOCUS_M * 1000.0)
    pitch_px = PITCH * (D + MICRO_F) / D / PIXEL
    recorded = doc["plenoptic"]["microimage_lattice"]["microimage_pitch_px"]
    assert abs(recorded - pitch_px) < 1e-6 * pitch_px, "microimage pitch %r px, thin lens %r" % (recorded, pitch_px)
    assert doc["plenoptic"]["microimage_lattice"]["basis_px"] == meta_doc["microimage_lattice"]["basis_px"]


def test_hexagonal_grid_model_puts_every_lens_on_a_centre(args, exports):
    png, meta_path, folder, _ = exports["hex"]
    with open(os.path.join(folder, "eslf_hex.eslf.png.json"), encoding="utf-8") as f:
        model = json.load(f)["LensletGridModel"]
    with open(meta_path, encoding="utf-8") as f:
        lattice = json.load(f)["microimage_lattice"]
    assert model is not None and model["Orientation"] == "horz" and model["FirstPosShiftRow"] in (1, 2)
    assert abs(abs(model["Rot"]) - math.radians(3)) < 1e-6, "Rot %r rad, the array is turned 3 degrees" % model["Rot"]
    grid = lfbuild_hex_grid(model).reshape(-1, 2) - 1.0  # to 0-based pixels
    inside = (grid[:, 0] >= 0) & (grid[:, 0] <= W - 1) & (grid[:, 1] >= 0) & (grid[:, 1] <= H - 1)
    grid = grid[inside]
    origin = np.array(lattice["origin_px"], float)
    basis = np.array(lattice["basis_px"], float).T
    kl = np.linalg.solve(basis, (grid - origin).T).T
    off = np.abs((np.rint(kl) - kl) @ basis.T).max()
    assert off < 1e-6, "every grid point of the model is a microimage centre (largest miss %.3g px)" % off
    k, l = np.meshgrid(np.arange(-200, 200), np.arange(-200, 200))
    centres = origin + np.stack([k.ravel(), l.ravel()], axis=1) @ basis.T
    centres = centres[(centres[:, 0] >= 0) & (centres[:, 0] <= W - 1) & (centres[:, 1] >= 0) & (centres[:, 1] <= H - 1)]
    assert len(grid) >= 0.9 * len(centres), "the model covers %d of the %d centres in the image" % (len(grid), len(centres))


def test_rectangular_grid_model_is_null_with_the_reason(args, exports):
    _, _, folder, _ = exports["rect"]
    with open(os.path.join(folder, "eslf_rect.eslf.png.json"), encoding="utf-8") as f:
        doc = json.load(f)
    assert doc["LensletGridModel"] is None
    assert "hexagonal only" in doc["plenoptic"]["lenslet_grid_model"], doc["plenoptic"]["lenslet_grid_model"]


def test_a_scale_that_would_clip_is_refused(args, exports):
    png, _, _, _ = exports["rect"]
    folder = os.path.join(args.work, "eslf_refused")
    run = run_export(args, png, "--to", "eslf", folder, "-O", "scale=4", "-q")
    assert run.returncode == 2 and "-O scale=4 puts the largest value at" in run.stderr, run.stderr
    assert not os.path.exists(folder) and not [e for e in os.listdir(args.work) if "eslf_refused" in e]
