# SPDX-License-Identifier: AGPL-3.0-or-later
"""Render the scenes of scenes/report2018 and write the figures of docs/report2018.md.

Each scene is rendered to a linear OpenEXR file (+FE), so no value is clipped before the
exposure is chosen. The exposure is physical: scenes with `radiometry irradiance` write E / C,
C being the metadata's `sensor.radiometry.projected_solid_angle_sr`, which depends on the
camera (on d, for an array). Every such raw is shown as E / C_ref, C_ref being the C of
full_d1_8.pov, so that the array set-ups compare as one sensor at one exposure time would see
them. The thin-lens scenes use flat radiometry (each picture at its own exposure: their
irradiances differ by (F / 50 mm)^2 at f/8, as docs/report2018.md says).

Writes, for each scene <name>: <out>/<name>.png (the whole raw, 8-bit sRGB) and, for the scenes
with an array, <out>/<name>_zoom.png (the central `--zoom-px` pixels, enlarged `--zoom-scale`
times without interpolation), and prints one line per scene: seconds, the mean of E / C_ref over
the central half of the sensor, the share of black pixels.
"""
import argparse
import glob
import os
import sys

import numpy as np
import OpenImageIO as oiio

from plenoptic_lf.errors import DependencyError, MetadataError
from plenoptic_lf.images import ImageReadError, linear_to_srgb, read_image
from plenoptic_lf.metadata import read_metadata
from plenoptic_lf.povray import povray_command, run_povray

REFERENCE = "full_d1_8"


def render(povray, scene, work, size):
    name = os.path.splitext(os.path.basename(scene))[0]
    exr = os.path.join(work, name + ".exr")
    cmd = povray_command(povray, scene, exr, size, size, ["+L" + os.path.dirname(scene), "+FE", "-D", "-GS", "-GR",
                                                          "-GD"])
    run = run_povray(cmd)
    seconds = run.seconds
    if run.returncode != 0:
        text = run.output.replace("\r", "\n").strip().splitlines()
        raise RuntimeError("%s: povray exited %d:\n%s" % (scene, run.returncode,
                                                          "\n".join(text[-15:])))
    try:
        image = read_image(exr)[:, :, :3]
    except ImageReadError as e:
        raise RuntimeError(str(e)) from None
    try:
        meta = read_metadata(os.path.join(work, name + ".plenoptic.json"))
    except (MetadataError, DependencyError) as e:
        raise RuntimeError("%s: %s" % (os.path.join(work, name + ".plenoptic.json"), e)) from None
    return name, image, meta, seconds


def solid_angle(meta):
    """C of an irradiance render, None for a flat one."""
    return meta.projected_solid_angle_sr if meta.radiometry_model == "irradiance" else None


def to_srgb8(linear):
    return np.round(linear_to_srgb(linear) * 255).astype(np.uint8)


def write_png(path, rgb8):
    spec = oiio.ImageSpec(rgb8.shape[1], rgb8.shape[0], 3, oiio.UINT8)
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec):
        raise RuntimeError("cannot write %s: %s" % (path, oiio.geterror()))
    out.write_image(np.ascontiguousarray(rgb8))
    out.close()


def zoom(rgb8, px, scale):
    h, w = rgb8.shape[:2]
    px = min(px, h, w)
    y0, x0 = (h - px) // 2, (w - px) // 2
    crop = rgb8[y0:y0 + px, x0:x0 + px]
    return np.repeat(np.repeat(crop, scale, axis=0), scale, axis=1)


def central_mean(image):
    h, w = image.shape[:2]
    return float(image[h // 4:h - h // 4, w // 4:w - w // 4].mean())


def main(argv=None):
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    p = argparse.ArgumentParser(prog="report2018-figures", description=__doc__.split("\n\n")[0])
    p.add_argument("--povray", default=os.path.join(root, "build", "povray"))
    p.add_argument("--scenes", default=os.path.join(root, "scenes", "report2018"))
    p.add_argument("--out", default=os.path.join(root, "docs", "report2018"))
    p.add_argument("--work", default=None, help="scratch folder for the EXR renders (default: <out>/.work, removed)")
    p.add_argument("--size", type=int, default=480, help="pixels across (the sensor's width is fixed in mm)")
    p.add_argument("--zoom-px", type=int, default=64)
    p.add_argument("--zoom-scale", type=int, default=4)
    p.add_argument("--only", nargs="*", default=None, help="scene names (the reference is always rendered)")
    a = p.parse_args(argv)
    povray = os.path.abspath(a.povray)
    scenes = sorted(glob.glob(os.path.join(a.scenes, "*.pov")))
    names = [os.path.splitext(os.path.basename(s))[0] for s in scenes]
    if REFERENCE not in names:
        sys.exit("report2018-figures: %s.pov not found in %s" % (REFERENCE, a.scenes))
    if a.only:
        unknown = sorted(set(a.only) - set(names))
        if unknown:
            sys.exit("report2018-figures: no such scene: %s (scenes: %s)" % (", ".join(unknown), ", ".join(names)))
        scenes = [s for s, n in zip(scenes, names) if n in a.only or n == REFERENCE]
    os.makedirs(a.out, exist_ok=True)
    work = a.work or os.path.join(a.out, ".work")
    os.makedirs(work, exist_ok=True)
    scenes.sort(key=lambda s: not s.endswith(REFERENCE + ".pov"))   # the reference first
    c_ref = None
    try:
        for scene in scenes:
            name, image, meta, seconds = render(povray, scene, work, a.size)
            c = solid_angle(meta)
            if name == REFERENCE:
                c_ref = c
            shown = image * (c / c_ref) if c is not None else image
            rgb8 = to_srgb8(shown)
            write_png(os.path.join(a.out, name + ".png"), rgb8)
            if meta.array is not None:
                write_png(os.path.join(a.out, name + "_zoom.png"), zoom(rgb8, a.zoom_px, a.zoom_scale))
            black = float((image.max(axis=2) <= 0.0).mean())
            print("%-28s %6.1f s  mean %s %.3f  black %.3f" % (
                name, seconds, "E/C_ref" if c is not None else "flat   ", central_mean(shown), black),
                flush=True)
    except (RuntimeError, OSError) as e:
        sys.exit("report2018-figures: %s" % e)
    except KeyboardInterrupt:
        sys.exit(130)
    finally:
        if a.work is None:
            for f in glob.glob(os.path.join(work, "*")):
                os.remove(f)
            os.rmdir(work)
    return 0
