# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-decode requires OpenImageIO and says so in one line when it is missing.

Without OpenImageIO the decoder used to fall back to Pillow, which reads a 16-bit PNG as 8 bits
(and knows nothing of its gAMA chunk), and decode that silently. Here OpenImageIO is made
unimportable by a folder on PYTHONPATH whose OpenImageIO.py raises ImportError (numpy and Pillow
stay importable, so a fallback would still run), and a 16-bit linear render is decoded by the
in-tree launcher and by `python3 -m plenoptic_lf`:

  - exit status non-zero (1), exactly one line on stderr, 'plenoptic-decode: error: ...', naming
    the Debian package (python3-openimageio) and the pip package (OpenImageIO); no traceback;
    nothing written;
  - `--help` still works;
  - the library: plenoptic_lf imports, and read_raw raises an ImportError carrying that message;
  - positive control: with OpenImageIO importable the same command decodes (exit 0).
"""

import os
import shutil
import subprocess
import sys
import types

import pytest

import plenoptic_testing as pt

SCENE = """camera {
  plenoptic
  location <0, 0, -2>
  look_at <0, 0, 0>
  main_lens { thin_lens focal_length 50 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 }
  sensor { pixel_size 0.01 }
}
plane { -z, 0 pigment { rgb <0.8, 0.35, 0.05> } finish { emission 1 diffuse 0 ambient 0 } }
"""

BLOCKER = '''# Written by tests/ground_truth/test_decode_requires_oiio.py: OpenImageIO made unimportable.
raise ImportError("No module named 'OpenImageIO' (hidden by the test)", name="OpenImageIO")
'''


@pytest.fixture(scope="module")
def setup(args):
    """The render, and the environments that hide OpenImageIO (launcher; module from python/)."""
    png, _, _ = pt.render_ground_truth(args.povray, args.work, "no_oiio", SCENE, 96, 72)
    blocker = os.path.join(args.work, "no_oiio_path")
    shutil.rmtree(blocker, ignore_errors=True)
    os.makedirs(blocker)
    with open(os.path.join(blocker, "OpenImageIO.py"), "w") as f:
        f.write(BLOCKER)
    python_dir = os.path.abspath(args.python)
    env = dict(os.environ, PYTHONPATH=blocker, PYTHONDONTWRITEBYTECODE="1")
    env_module = dict(env, PYTHONPATH=blocker + os.pathsep + python_dir)
    return types.SimpleNamespace(png=png, env=env, env_module=env_module)


def test_blocker_works(setup):
    """The blocker works, and a fallback would have what it needs."""
    probe = subprocess.run([sys.executable, "-c", "import numpy, PIL\ntry:\n import OpenImageIO\n"
                            "except ImportError as e:\n print('blocked', e)"], env=setup.env, capture_output=True, text=True)
    assert (probe.returncode == 0 and probe.stdout.startswith("blocked")), (
        "with the blocker on PYTHONPATH, numpy and Pillow import and OpenImageIO does not: %r %r"
        % (probe.stdout.strip(), probe.stderr.strip()[-300:]))


@pytest.mark.parametrize("label", ["tools/plenoptic-decode", "python3 -m plenoptic_lf"])
def test_command_without_oiio(args, setup, label):
    if label == "tools/plenoptic-decode":
        command, environment = pt.decoder(args.tools), setup.env
    else:
        command, environment = [sys.executable, "-m", "plenoptic_lf"], setup.env_module
    png = setup.png
    out = os.path.join(args.work, "no_oiio_%s.lightfield" % ("module" if "-m" in command else "launcher"))
    shutil.rmtree(out, ignore_errors=True)
    run = subprocess.run(command + [png, "-o", out], env=environment, capture_output=True, text=True,
                         cwd=args.work)
    lines = [l for l in run.stderr.splitlines() if l.strip()]
    assert (run.returncode != 0 and len(lines) == 1 and lines[0].startswith("plenoptic-decode: error:")
                 and "python3-openimageio" in lines[0] and "pip install OpenImageIO" in lines[0]
                 and "Traceback" not in run.stderr and not os.path.exists(os.path.join(out, "contact_sheet.png"))), ("%s without OpenImageIO: exit %d (want non-zero), stderr %r (want one line naming "
                 "python3-openimageio and 'pip install OpenImageIO'), outputs written: %s"
                 % (label, run.returncode, run.stderr.strip()[-500:], os.path.exists(out)))
    assert (run.returncode == 1), ("%s without OpenImageIO: exit status %d (want 1, as for a missing numpy)"
                 % (label, run.returncode))
    help_run = subprocess.run(command + ["--help"], env=environment, capture_output=True, text=True,
                              cwd=args.work)
    assert (help_run.returncode == 0 and help_run.stdout.startswith("usage: plenoptic-decode")), ("%s --help without OpenImageIO: exit %d, %r" % (label, help_run.returncode,
                                                                 help_run.stdout[:60] + help_run.stderr[-200:]))


def test_library_without_oiio(setup):
    """The library: importable without OpenImageIO, read_raw refuses with the same message."""
    png = setup.png
    snippet = ("import plenoptic_lf\n"
               "try:\n"
               "    plenoptic_lf.read_raw(%r)\n"
               "    print('read')\n"
               "except ImportError as e:\n"
               "    print('ImportError', type(e).__name__, e)\n" % png)
    run = subprocess.run([sys.executable, "-c", snippet], env=setup.env_module, capture_output=True, text=True)
    assert (run.returncode == 0 and run.stdout.startswith("ImportError") and "python3-openimageio" in run.stdout
                 and "pip install OpenImageIO" in run.stdout), ("library without OpenImageIO: import plenoptic_lf works and read_raw raises an ImportError "
                 "naming both packages: %r %r" % (run.stdout.strip(), run.stderr.strip()[-300:]))


def test_decodes_with_oiio(args, setup):
    """Positive control."""
    png, launcher = setup.png, pt.decoder(args.tools)
    out = os.path.join(args.work, "no_oiio_control.lightfield")
    shutil.rmtree(out, ignore_errors=True)
    run = subprocess.run(launcher + [png, "-o", out, "-q", "--no-gif"], capture_output=True, text=True)
    assert (run.returncode == 0 and os.path.exists(os.path.join(out, "contact_sheet.png"))), "with OpenImageIO the same render decodes (exit %d, %r)" % (run.returncode, run.stderr.strip()[-300:])

