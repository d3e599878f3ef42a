# SPDX-License-Identifier: AGPL-3.0-or-later
"""The installed Python tools come from the one table and run under the Python the build found.

source/tools/python_tools.cmake (the install rules of the Python tools, which
source/tools/CMakeLists.txt includes) is configured in a project of its own, installed into a
temporary prefix and the prefix moved; then:

1. P/bin holds one launcher per tool of python/pyproject.toml's [project.scripts] and nothing else,
   P/lib/python3/dist-packages/plenoptic_lf the package with the metadata's schema (a file, the
   bytes of docs/metadata.schema.json, not the source tree's link);
2. each launcher's first line names the Python given to CMake (Python3_EXECUTABLE): here a
   wrapper of /usr/bin/python3 that leaves a mark when it runs;
3. with a python3 that lacks numpy first on PATH (checked), every launcher's --help works, runs
   under that recorded Python (its mark appears) and loads plenoptic_lf from the moved prefix;
   the decoder decodes a render there.
"""
import os
import shutil
import tomllib

import plenoptic_testing as pt

NO_NUMPY_PYTHON = ('#!/bin/sh\n# Written by tests/install/test_install_python_tools.py: a python3 without numpy.\n'
                   'exec /usr/bin/python3 -S "$@"\n')
RECORDED_PYTHON = ('#!/bin/sh\n# Written by tests/install/test_install_python_tools.py: /usr/bin/python3, marked.\n'
                   'echo ran >> %s\nexec /usr/bin/python3 "$@"\n')
PROJECT = """cmake_minimum_required(VERSION 3.21)
project(python_tools_install NONE)
include("%s")
"""
SCENE = """camera { plenoptic location <0, 0, -2> look_at 0
  main_lens { thin_lens focal_length 50 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.1 focal_length 0.4 distance 0.4 }
  sensor { pixel_size 0.01 } }
sphere { 0, 0.3 pigment { checker rgb 1 rgb <1, 0.2, 0.1> scale 0.1 } finish { emission 1 diffuse 0 } }
"""


def script(path, text):
    with open(path, "w") as f:
        f.write(text)
    os.chmod(path, 0o755)
    return path


def test_install_python_tools(args):
    source = os.path.realpath(args.source_dir)
    work = os.path.realpath(args.work)
    shutil.rmtree(work, ignore_errors=True)
    for d in ("project", "bin-no-numpy", "recorded", "run"):
        os.makedirs(os.path.join(work, d))
    with open(os.path.join(source, "python", "pyproject.toml"), "rb") as f:
        tools = tomllib.load(f)["project"]["scripts"]
    mark = os.path.join(work, "recorded", "ran")
    recorded = script(os.path.join(work, "recorded", "python3"), RECORDED_PYTHON % mark)
    script(os.path.join(work, "bin-no-numpy", "python3"), NO_NUMPY_PYTHON)
    with open(os.path.join(work, "project", "CMakeLists.txt"), "w") as f:
        f.write(PROJECT % os.path.join(source, "source", "tools", "python_tools.cmake"))

    build, prefix, moved = (os.path.join(work, d) for d in ("build", "prefix", "moved"))
    r = pt.run_process([args.cmake, "-S", os.path.join(work, "project"), "-B", build,
                        "-DPython3_EXECUTABLE=" + recorded], cwd=work, timeout=300)
    assert r.returncode == 0, "configuring the install rules failed:\n" + r.output[-3000:]
    r = pt.run_process([args.cmake, "--install", build, "--prefix", prefix], cwd=work, timeout=300)
    assert r.returncode == 0, "cmake --install failed:\n" + r.output[-3000:]
    os.rename(prefix, moved)

    # 1. The layout.
    assert sorted(os.listdir(os.path.join(moved, "bin"))) == sorted(tools), (
        "P/bin holds %s, the table %s" % (sorted(os.listdir(os.path.join(moved, "bin"))), sorted(tools)))
    package = os.path.join(moved, "lib", "python3", "dist-packages", "plenoptic_lf")
    schema = os.path.join(package, "metadata.schema.json")
    assert os.path.isfile(schema) and not os.path.islink(schema), "the schema is installed as a file: %s" % schema
    with open(schema, "rb") as a, open(os.path.join(source, "docs", "metadata.schema.json"), "rb") as b:
        assert a.read() == b.read(), "the installed schema is docs/metadata.schema.json"
    for name in ("__init__.py", "cli.py", "targets.py", os.path.join("dataset", "cli.py"), "py.typed"):
        assert os.path.isfile(os.path.join(package, name)), "not installed: plenoptic_lf/" + name

    # 2. The recorded Python on every launcher's first line.
    for tool in tools:
        with open(os.path.join(moved, "bin", tool)) as f:
            first = f.readline().rstrip("\n")
        assert first == "#!" + recorded, "P/bin/%s starts %r, not #!%s" % (tool, first, recorded)

    # 3. Run with a python3 without numpy first on PATH.
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "PLENOPTIC_PROJECT")}
    env["PATH"] = os.path.join(work, "bin-no-numpy") + os.pathsep + "/usr/bin:/bin"
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    control = pt.run_process(["python3", "-c", "import numpy"], env=env, cwd=os.path.join(work, "run"))
    assert control.returncode != 0 and "numpy" in control.output, "the python3 first on PATH lacks numpy (control)"
    for tool, entry in tools.items():
        if os.path.exists(mark):
            os.remove(mark)
        r = pt.run_process([os.path.join(moved, "bin", tool), "--help"], env=env, cwd=os.path.join(work, "run"),
                           separate=True)
        assert r.returncode == 0 and r.stdout.startswith("usage: " + tool), (
            "installed %s --help with a python3 without numpy first on PATH: exit %d, %r"
            % (tool, r.returncode, r.stdout[:80] + r.stderr[-500:]))
        assert os.path.exists(mark), "installed %s did not run under the recorded Python %s" % (tool, recorded)
        probe = ("import runpy, sys; runpy.run_path(%r, run_name='probe'); print(sys.modules[%r].__file__)"
                 % (os.path.join(moved, "bin", tool), entry.split(":")[0]))
        r = pt.run_process([recorded, "-c", probe], env=env, cwd=os.path.join(work, "run"), separate=True)
        assert r.stdout.strip().startswith(package + os.sep), (
            "installed %s loads %s from %r, not the moved prefix" % (tool, entry, r.stdout.strip() + r.stderr[-300:]))

    png, _, _ = pt.render_ground_truth(args.povray, os.path.join(work, "run"), "installed", SCENE, 96, 72)
    r = pt.run_process([os.path.join(moved, "bin", "plenoptic-decode"), png, "-q", "--no-gif", "--no-npy", "-o",
                        os.path.join(work, "run", "decoded")], env=env, cwd=os.path.join(work, "run"), timeout=300)
    assert r.returncode == 0 and os.path.isfile(os.path.join(work, "run", "decoded", "contact_sheet.png")), (
        "the installed plenoptic-decode under a python3 without numpy on PATH:\n" + r.output[-2000:])
