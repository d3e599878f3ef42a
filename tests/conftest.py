# SPDX-License-Identifier: AGPL-3.0-or-later
"""pytest configuration of the render and tool tests: the options ctest passes (tests/CMakeLists.txt)
and the fixtures the tests take them from. Every option may also come from the environment
(PLENOPTIC_TEST_<OPTION>, upper case, dashes as underscores, e.g. PLENOPTIC_TEST_POVRAY), and most
have a default in a build tree at build/ beside tests/, so that

    /usr/bin/python3 -m pytest tests/camera/test_determinism.py

works after tools/build. The shared helper is tests/pylib/plenoptic_testing (docs/testing.md).
"""
import os
import sys
import types

import pytest

TESTS = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(TESTS)
BUILD = os.path.join(SOURCE, "build")
sys.path.insert(0, os.path.join(TESTS, "pylib"))

# option -> (help, default when neither the command line nor the environment gives it)
OPTIONS = {
    "povray": ("our povray binary", os.path.join(BUILD, "povray")),
    "project": ("the plenoptic-project binary", os.path.join(BUILD, "plenoptic-project")),
    "lens-data": ("the plenoptic-lens-data binary (plenoptic-lens's optics)", os.path.join(BUILD, "plenoptic-lens-data")),
    "truth-bench": ("the plenoptic_microimage_truth bench program (source/bench)",
                    os.path.join(BUILD, "source", "bench", "plenoptic_microimage_truth")),
    "work": ("scratch directory (created); default build/test-output/pytest/<test file>", None),
    "tools": ("the tools/ folder (the plenoptic-decode launcher)", os.path.join(SOURCE, "tools")),
    "python": ("the folder holding the plenoptic_lf package", os.path.join(SOURCE, "python")),
    "upstream": ("the unpacked Debian POV-Ray source (UPSTREAM_DIR; distribution/ inside)", None),
    "patched-source": ("the patched POV-Ray source tree the build compiles (build/_povray)",
                       os.path.join(BUILD, "_povray")),
    "project-version": ("the project's version (CMake's PROJECT_VERSION)", None),
    "build-dir": ("the build directory", BUILD),
    "source-dir": ("the source directory", SOURCE),
    "cmake": ("the cmake command", "cmake"),
    "reference-povray": ("Debian's packaged povray", "/usr/bin/povray"),
    # tests/compat/test_parse_distribution.py (the ci subset by default; tests/compat/full-sweep)
    "compat-mode": ("parse sweep: ci (a subset) or full", "ci"),
    "compat-every": ("parse sweep, ci mode: keep every Nth non-include item", "8"),
    "compat-timeout": ("parse sweep: seconds per parse", "120"),
    "compat-known": ("parse sweep, full mode: fails_with_both.txt to compare with", None),
    "compat-only": ("parse sweep: only items whose name matches this regular expression", None),
}


def pytest_addoption(parser):
    group = parser.getgroup("plenoptic", "povray-plenoptic tests")
    for name, (text, _) in OPTIONS.items():
        group.addoption("--" + name, dest=name.replace("-", "_"), default=None, help=text)


def option(config, name):
    value = config.getoption(name.replace("-", "_"))
    if value is None:
        value = os.environ.get("PLENOPTIC_TEST_" + name.upper().replace("-", "_"))
    if value is None:
        value = OPTIONS[name][1]
    if value is None and name == "upstream":
        found = sorted(d for d in (os.listdir(os.path.join(BUILD, "_upstream")) if os.path.isdir(
            os.path.join(BUILD, "_upstream")) else []) if d.startswith("povray-"))
        value = os.path.join(BUILD, "_upstream", found[0]) if found else None
    return value


def pytest_configure(config):
    python_dir = option(config, "python")
    if python_dir and os.path.abspath(python_dir) not in sys.path:
        sys.path.insert(0, os.path.abspath(python_dir))


@pytest.fixture(scope="module")
def args(request):
    """The options as attributes (povray, project, work, tools, python, upstream, version, ...);
    the work directory made absolute and created. A missing required option fails the test."""
    config = request.config
    ns = types.SimpleNamespace(**{n.replace("-", "_"): option(config, n) for n in OPTIONS})
    if ns.work is None:
        rel = os.path.relpath(str(request.path), TESTS)
        ns.work = os.path.join(BUILD, "test-output", "pytest", os.path.splitext(rel)[0])
    ns.work = os.path.abspath(ns.work)
    os.makedirs(ns.work, exist_ok=True)
    if ns.python:
        ns.python = os.path.abspath(ns.python)
    return ns

