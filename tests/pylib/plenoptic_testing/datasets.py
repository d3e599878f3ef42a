# SPDX-License-Identifier: AGPL-3.0-or-later
"""Shared by the plenoptic-dataset tests (tests/dataset): a small scene and spec, running the
command, and checking a data set's manifest against checksums computed here."""

import hashlib
import json
import os
import subprocess
import sys

import numpy as np

from . import read_pixels, write_text

SCENE = """// SPDX-License-Identifier: AGPL-3.0-or-later
#version 3.7;
global_settings { assumed_gamma 1.0 }
#ifndef (Focus) #declare Focus = 1.5; #end
#ifndef (Sphere_X) #declare Sphere_X = 0; #end
#ifndef (Slow_Item) #declare Slow_Item = -1; #end
#ifndef (Dataset_Item) #declare Dataset_Item = 0; #end
#ifndef (Diffract) #declare Diffract = 0; #end
#ifndef (No_Wall) #declare No_Wall = 0; #end
#ifndef (Dataset_Samples) #declare Dataset_Samples = 4; #end
#ifndef (Dataset_Depth_Map) #declare Dataset_Depth_Map = 0; #end
camera {
  plenoptic location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length 50 f_number 2.5 focus_distance Focus }
  microlens_array { hexagonal pitch 0.1 focal_length 0.25 distance 0.25 }
  sensor { pixel_size 0.02 }
  samples ((Dataset_Item = Slow_Item) ? 4000 : Dataset_Samples)
  depth_map (Dataset_Depth_Map)
  #if (Diffract) radiometry irradiance diffraction #end
}
#declare Glow = finish { emission 1 diffuse 0 ambient 0 }
sphere { <Sphere_X, 0, 1.2>, 0.012 pigment { checker rgb <0.9, 0.3, 0.2> rgb <0.2, 0.4, 0.9> scale 0.004 } finish { Glow } }
#if (!No_Wall) plane { z, 2.5 pigment { bozo color_map { [0 rgb 0.2] [1 rgb 0.9] } scale 0.05 } finish { Glow } } #end
"""

SPEC = """scene = "scene.pov"
width = 96
height = 72
%s
[options]
samples = 4
depth_map = true

[sweep]
Focus = %s

[random]
count = 2
seed = 11
Sphere_X = { uniform = [-0.01, 0.01] }
"""


def write_spec(work, name, focus="[1.0, 1.5]", extra=""):
    os.makedirs(work, exist_ok=True)
    write_text(os.path.join(work, "scene.pov"), SCENE)
    path = os.path.join(work, name + ".toml")
    write_text(path, SPEC % (extra, focus))
    return path


def dataset(args, *argv, **kwargs):
    env = dict(os.environ, PYTHONPATH=args.python, PLENOPTIC_POVRAY=args.povray)
    env.update(kwargs.pop("env", {}))
    return subprocess.run([sys.executable, "-m", "plenoptic_lf.dataset"] + list(argv), capture_output=True, text=True,
                          env=env, timeout=kwargs.pop("timeout", 600))


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def manifest(out):
    with open(os.path.join(out, "manifest.jsonl")) as f:
        return [json.loads(line) for line in f if line.strip()]


def check_manifest(out, expected_count):
    """Every line's files exist with the sizes and SHA-256 computed here; returns {id: record}."""
    records = manifest(out)
    assert len(records) == expected_count, "%d manifest lines, %d items" % (len(records), expected_count)
    assert [r["index"] for r in records] == sorted(r["index"] for r in records), "lines in item order"
    for r in records:
        folder = os.path.join(out, "items", r["id"])
        for name, entry in r["files"].items():
            path = os.path.join(folder, name)
            assert os.path.getsize(path) == entry["bytes"] and sha256(path) == entry["sha256"], (
                "%s: size and SHA-256 as the manifest says" % path)
        assert r["image"] in r["files"] and r["id"] + ".plenoptic.json" in r["files"], "image and metadata listed"
        assert r["render_seconds"] > 0 and r["host"], "render time and host recorded"
    return {r["id"]: r for r in records}


def pixels(path):
    return np.nan_to_num(read_pixels(path), nan=-7.0)
