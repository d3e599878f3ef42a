# SPDX-License-Identifier: AGPL-3.0-or-later
"""Scenes of POV-Ray's own distribution render the same with our build and with Debian's packaged
povray (OpenImageIO's idiff compares them): the build is faithful to Debian's before our camera
changes anything.

ctest stock_scenes_match_debian runs test_stock_scene (DEFAULT_SCENES: small, quick scenes that
exercise CSG, textures, normals, media, focal blur, isosurfaces, radiosity-free lighting);
compat_stock_cameras_match_debian runs test_stock_camera (one scene per other camera type).
"""
import os

import pytest

import plenoptic_testing as pt

DEFAULT_SCENES = [
    "advanced/biscuit.pov",
    "advanced/woodbox.pov",
    "advanced/chess2.pov",
    "advanced/optics.pov",
    "advanced/quilt1.pov",
    "camera/focalblur.pov",
    "camera/fisheye.pov",
    "advanced/isocacti.pov",
]

CAMERA_SCENES = [
    "camera/orthographic.pov",
    "camera/spherical.pov",
    "camera/cylinder1.pov",
    "camera/ultra_wide_angle.pov",
    "camera/panoramic.pov",
    "camera/omnimax.pov",
]

WIDTH, HEIGHT = 160, 120

# idiff thresholds: builds with different compilers/flags may differ by rounding in a
# few pixels; anything beyond 1/255 in more than 0.5% of pixels, or any pixel off by
# more than 0.1, is a real difference.
IDIFF_ARGS = ["-fail", "0.004", "-failpercent", "0.5", "-hardfail", "0.1",
              "-warn", "0.004", "-warnpercent", "0.01"]


def render(povray, scene, out_png):
    """One render thread: some stock scenes (quilt1's quilted normal) differ from run to run
    with 2 threads even in Debian's own binary."""
    if os.path.exists(out_png):
        os.remove(out_png)
    run = pt.run_povray(povray, scene, out_png, WIDTH, HEIGHT, timeout=600,
                        options=("-D", "-P", "+FN8", "+L" + os.path.dirname(scene), "-GS", "-GR", "+WT1"))
    assert run.returncode == 0 and not run.timed_out and os.path.exists(out_png), (
        "%s failed on %s (exit %s%s):\n%s" % (povray, scene, run.returncode,
                                             ", time limit" if run.timed_out else "", run.output[-2000:]))


def compare(args, rel):
    reference = pt.require_debian_povray(args.reference_povray)
    pt.idiff_command()
    assert args.upstream, "no --upstream (the unpacked Debian POV-Ray source)"
    scene = os.path.join(args.upstream, "distribution", "scenes", rel)
    stem = rel.replace("/", "_").replace(".pov", "")
    ours = os.path.join(args.work, stem + ".ours.png")
    ref = os.path.join(args.work, stem + ".debian.png")
    render(args.povray, scene, ours)
    render(reference, scene, ref)
    diff_png = os.path.join(args.work, stem + ".diff.png")
    code, text = pt.idiff(ref, ours, IDIFF_ARGS, diff_out=diff_png)
    assert code in (0, 1), "%s: idiff exit %d; diff image %s\n%s" % (rel, code, diff_png, text)  # 1: warning only
    if os.path.exists(diff_png):
        os.remove(diff_png)


@pytest.mark.parametrize("rel", DEFAULT_SCENES)
def test_stock_scene(args, rel):
    compare(args, rel)


@pytest.mark.parametrize("rel", CAMERA_SCENES)
def test_stock_camera(args, rel):
    compare(args, rel)
