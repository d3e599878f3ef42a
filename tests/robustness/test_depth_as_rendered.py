# SPDX-License-Identifier: AGPL-3.0-or-later
"""The depth map is computed as the image is rendered.

Before, with `depth_map` every render thread filled the whole depth map before its first pixel:
no progress, Ctrl-C ignored for as long as that took, W*H floats allocated up front, every row
computed for a +SR/+ER partial render too. These tests fail on that code:

- stop: a 6000x6000 depth render (36 million chief rays before the first pixel, before) must
  report pixels done within PROGRESS_SECONDS of its render phase; it is then sent SIGINT and
  must be gone within STOP_SECONDS, leaving no image, metadata or depth map.
- partial: a 20x20 region in the middle of a 6000x6000 image. The process's peak memory must stay
  far below the 144 MB a whole depth map takes; the region's depth and pixels must equal those of
  an independent 20x20 render of the same camera (with even sizes the two grids put the same
  sensor pixels there: pixel i of a W-wide image sits at (i - (W - 1) / 2) pixels from the axis),
  and every pixel outside the region must read -1 (docs/ground-truth.md).

Run by ctest as robustness_depth_as_rendered (the options come through tests/conftest.py).
"""
import os
import re
import signal
import subprocess
import time

import numpy as np

import plenoptic_testing as pt

SCENE = """\
// SPDX-License-Identifier: AGPL-3.0-or-later
#version 3.7;
global_settings { assumed_gamma 1.0 }
camera {
  plenoptic
  location <0, 0.5, -2>
  look_at <0, 0.3, 0>
  main_lens { thin_lens focal_length 8 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 }
  sensor { pixel_size %(pixel)s }
  samples %(samples)d
  depth_map
}
light_source { <-3, 5, -4> color rgb 1 }
sky_sphere { pigment { gradient y color_map { [0 rgb <0.75, 0.85, 1>] [1 rgb <0.3, 0.45, 0.8>] } } }
plane { y, 0 pigment { checker color rgb 0.9 color rgb 0.2 scale 0.25 } }
sphere { <0, 0.3, 0>, 0.3 pigment { color rgb <0.9, 0.3, 0.2> } }
"""
PROGRESS = re.compile(rb"Rendered (\d+) of (\d+) pixels")
RENDERING = b"==== [Rendering...]"
# The first block of pixels takes milliseconds; before the fix, 36 million chief rays came first.
PROGRESS_SECONDS = 5
# The stop check runs between rows of render blocks; POV-Ray polls for the signal every 200 ms.
# Generous for a loaded two-core machine; before the fix the stop took the whole depth pass.
STOP_SECONDS = 10
# A whole 6000x6000 depth map is 144 MB; POV-Ray itself keeps the image in a file-backed buffer.
PEAK_MEMORY_MB = 100


def scene_dir(args, name, pixel, samples):
    path = os.path.join(args.work, name)
    os.makedirs(path, exist_ok=True)
    for f in os.listdir(path):
        os.remove(os.path.join(path, f))
    with open(os.path.join(path, "scene.pov"), "w") as f:
        f.write(SCENE % {"pixel": pixel, "samples": samples})
    return path


def command(povray, width, height, extra=()):
    return [povray, "+Iscene.pov", "+Oimage.png", "+W%d" % width, "+H%d" % height,
            "-D", "-P", "-GS", "-GR", "+FN16", "File_Gamma=1.0"] + list(extra)


def peak_memory_mb(proc, timeout):
    """The process's peak resident memory (VmHWM of /proc/PID/status, read every 50 ms until it
    exits). Not ru_maxrss: on Linux that keeps the peak from before exec, i.e. this test's own."""
    peak_kb = 0
    deadline = time.monotonic() + timeout
    while proc.poll() is None and time.monotonic() < deadline:
        try:
            with open("/proc/%d/status" % proc.pid) as f:
                for line in f:
                    if line.startswith("VmHWM:"):
                        peak_kb = max(peak_kb, int(line.split()[1]))
        except (FileNotFoundError, ProcessLookupError, ValueError):
            pass
        time.sleep(0.05)
    if proc.poll() is None:
        proc.kill()
        proc.wait()
        raise AssertionError("the render did not finish in %d s" % timeout)
    return peak_kb / 1024.0


def test_progress_at_once_and_stop_within_seconds_of_sigint(args):
    cwd = scene_dir(args, "stop", "0.0025", 4)
    proc = subprocess.Popen(command(args.povray, 6000, 6000, ["+WT2"]), cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)
    os.set_blocking(proc.stdout.fileno(), False)
    out = b""
    rendering_at = signalled_at = None
    started = time.monotonic()
    try:
        while proc.poll() is None and time.monotonic() - started < 240:
            try:
                chunk = os.read(proc.stdout.fileno(), 65536) or b""
            except BlockingIOError:
                chunk = b""
            out += chunk
            now = time.monotonic()
            if rendering_at is None and RENDERING in out:
                rendering_at = now
            # Once the render phase has begun: SIGINT at the first pixels done, or after
            # PROGRESS_SECONDS without any (then the progress assertion below fails).
            if signalled_at is None and rendering_at is not None:
                progressed = any(int(d) > 0 for d, _ in PROGRESS.findall(out))
                if progressed or now - rendering_at > PROGRESS_SECONDS:
                    proc.send_signal(signal.SIGINT)
                    signalled_at = now
                    progress_seconds = now - rendering_at
            if not chunk:
                time.sleep(0.02)
        proc.wait(timeout=5)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    stopped_at = time.monotonic()
    out += proc.stdout.read() or b""
    text = out.decode("utf-8", errors="replace")
    assert signalled_at is not None, "the render phase did not begin in 240 s:\n" + text[-2000:]
    stopped_after = stopped_at - signalled_at
    done = [int(d) for d, _ in PROGRESS.findall(out)]
    print("first pixels %.1f s into the render phase; %d progress lines, last %s pixels; exit %d %.1f s after SIGINT" %
          (progress_seconds, len(done), done[-1] if done else "?", proc.returncode, stopped_after))
    assert progress_seconds <= PROGRESS_SECONDS, (
        "no pixel was done %.1f s into the render phase (the depth map must not come first)" % progress_seconds)
    assert stopped_after <= STOP_SECONDS, (
        "the render took %.1f s to stop after SIGINT (at most %d s)\n%s" % (stopped_after, STOP_SECONDS, text[-2000:]))
    assert proc.returncode != 0, "the interrupted render exited 0"
    left = sorted(f for f in os.listdir(cwd) if f not in ("scene.pov", "image.pov-state"))
    assert left == [], "a cancelled render left %s behind" % left


def test_partial_render_computes_and_holds_only_its_region(args):
    W = H = 6000
    first, last = 2990, 3009   # a 20x20 region at the centre (0-based; +SC/+EC/+SR/+ER count from 1)
    cwd = scene_dir(args, "partial", "0.001", 1)
    with open(os.path.join(cwd, "output.txt"), "wb") as log:
        proc = subprocess.Popen(command(args.povray, W, H, ["+WT2"] + ["%s%d" % (o, v + 1) for o, v in
                                                (("+SC", first), ("+EC", last), ("+SR", first), ("+ER", last))]),
                                cwd=cwd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        peak_mb = peak_memory_mb(proc, timeout=900)
    with open(os.path.join(cwd, "output.txt"), "rb") as log:
        text = log.read().decode("utf-8", errors="replace")
    assert proc.returncode == 0, text[-2000:]
    print("peak resident memory of the partial render: %.0f MB" % peak_mb)
    assert peak_mb < PEAK_MEMORY_MB, "a 20x20 region of a 6000x6000 depth render peaked at %.0f MB" % peak_mb

    depth = pt.read_pixels(os.path.join(cwd, "image.depth.exr"))[..., 0]
    assert depth.shape == (H, W), "the depth map is %s, the image %dx%d" % (depth.shape, W, H)
    inside = np.zeros((H, W), bool)
    inside[first:last + 1, first:last + 1] = True
    outside_wrong = int(np.count_nonzero(depth[~inside] != -1))
    assert outside_wrong == 0, "%d pixels outside the region do not read -1" % outside_wrong

    # The reference: the same camera, a 20x20 image, rendered whole.
    ref = scene_dir(args, "partial_reference", "0.001", 1)
    res = subprocess.run(command(args.povray, 20, 20, ["+WT1"]), cwd=ref, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         stdin=subprocess.DEVNULL, timeout=300)
    assert res.returncode == 0, res.stdout.decode(errors="replace")[-2000:]
    want = pt.read_pixels(os.path.join(ref, "image.depth.exr"))[..., 0]
    got = depth[first:last + 1, first:last + 1]
    assert np.isfinite(want).sum() > 100, "the reference region sees too little of the scene"
    assert np.array_equal(got, want), "region depth differs from the 20x20 render in %d pixels (max %g)" % (
        int(np.count_nonzero(got != want)), float(np.nanmax(np.abs(np.where(got == want, 0, got - want)))))
    image = pt.read_pixels(os.path.join(cwd, "image.png"))[first:last + 1, first:last + 1]
    want_image = pt.read_pixels(os.path.join(ref, "image.png"))
    assert np.array_equal(image, want_image), "region pixels differ from the 20x20 render"

