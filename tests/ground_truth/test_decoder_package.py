# SPDX-License-Identifier: AGPL-3.0-or-later
"""The Python tools are one package, python/plenoptic_lf, with its dependencies declared and
its commands in one table.

Checks, without rendering anything:
  - python/pyproject.toml: name plenoptic-lf, the project's version (CMake's PROJECT_VERSION,
    also plenoptic_lf.__version__), licence, Python >= 3.11 (tomllib), the table of tools
    ([project.scripts]: plenoptic-decode, plenoptic-dataset, plenoptic-targets; the source
    tree's bench and report2018-figures apart);
  - its dependencies are exactly the third-party modules the package imports;
  - every file starts with the SPDX header;
  - with only python/ on sys.path every module imports and the public API (__all__) is there;
    `python3 -m plenoptic_lf --help` and the in-tree launcher tools/plenoptic-decode print the
    same usage;
  - the in-tree launchers tools/<tool> are source/tools/launcher.py.in filled in from the table
    for /usr/bin/python3, one per tool and no other, and run under /usr/bin/python3 although the
    python3 first on PATH lacks numpy (it used to be `#!/usr/bin/env python3`, which then failed
    with "this Python lacks numpy");
  - `pip install --no-deps --no-build-isolation` of a copy of python/ into a throwaway venv
    gives every command of the table and the metadata's schema (needs Debian's python3-venv;
    said and skipped without it).
"""

import ast
import os
import shutil
import subprocess
import sys

import pytest

import plenoptic_testing as pt

# Import name -> distribution name on PyPI, for every third-party module the package may import.
DISTRIBUTIONS = {"numpy": "numpy", "scipy": "scipy", "PIL": "Pillow", "OpenImageIO": "OpenImageIO",
                 "jsonschema": "jsonschema", "cv2": "opencv-python"}
# Imported only by the modules named, declared in [project.optional-dependencies] (extra: name).
OPTIONAL_IMPORTS = {"cv2": ("calibration", {"calibration.py"})}
# The table of tools (python/pyproject.toml).
SCRIPTS = {"plenoptic-decode": "plenoptic_lf.cli:main", "plenoptic-dataset": "plenoptic_lf.dataset.cli:main",
           "plenoptic-targets": "plenoptic_lf.targets:main", "plenoptic-lens": "plenoptic_lf.lens_tool:main",
           "plenoptic-export": "plenoptic_lf.export.cli:main"}
SOURCE_TREE_SCRIPTS = {"bench": "plenoptic_bench.cli:main", "report2018-figures": "plenoptic_report2018.figures:main",
                       "calibration-loop": "plenoptic_lf.calibration:main"}
# A python3 that lacks numpy (site-packages off), first on PATH.
NO_NUMPY_PYTHON = '#!/bin/sh\n# Written by tests/ground_truth/test_decoder_package.py: a python3 without numpy.\n' \
                  'exec /usr/bin/python3 -S "$@"\n'


def requirement_name(requirement):
    """'numpy>=1.21' -> 'numpy' (PEP 508 name, up to the first version or marker character)."""
    name = requirement
    for stop in "<>=!~;[ (":
        name = name.split(stop)[0]
    return name.strip()


def package_modules(package_dir):
    """The package's .py files (its subpackages' too), relative to package_dir."""
    return sorted(os.path.relpath(os.path.join(d, n), package_dir) for d, _, files in os.walk(package_dir)
                  for n in files if n.endswith(".py") and "__pycache__" not in d)


def third_party_imports(package_dir):
    """Top-level names of the absolute imports in the package's modules that are not stdlib."""
    found = {}
    for name in package_modules(package_dir):
        tree = ast.parse(open(os.path.join(package_dir, name)).read(), name)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                modules = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                modules = [node.module]
            else:
                continue
            for module in modules:
                top = module.split(".")[0]
                if top not in sys.stdlib_module_names:
                    found.setdefault(top, set()).add(name)
    return found


def test_decoder_package(args):
    assert args.project_version, "--project-version (CMake's PROJECT_VERSION) is needed"
    args.version = args.project_version
    python_dir = os.path.abspath(args.python)
    package_dir = os.path.join(python_dir, "plenoptic_lf")
    os.makedirs(args.work, exist_ok=True)

    import tomllib
    with open(os.path.join(python_dir, "pyproject.toml"), "rb") as f:
        pyproject = tomllib.load(f)
    project = pyproject.get("project", {})
    assert (project.get("name") == "plenoptic-lf" and project.get("version") == args.version), ("pyproject.toml: name %r, version %r (want 'plenoptic-lf', the project's %r)"
                 % (project.get("name"), project.get("version"), args.version))
    licence = project.get("license")
    licence = licence.get("text") if isinstance(licence, dict) else licence
    assert (licence == "AGPL-3.0-or-later" and project.get("requires-python") == ">=3.11"), "pyproject.toml: license %r, requires-python %r" % (licence, project.get("requires-python"))
    assert project.get("scripts") == SCRIPTS, "pyproject.toml: scripts %r (want %r)" % (project.get("scripts"), SCRIPTS)
    tree_only = pyproject.get("tool", {}).get("plenoptic", {}).get("source-tree-scripts")
    assert tree_only == SOURCE_TREE_SCRIPTS, "pyproject.toml: tool.plenoptic.source-tree-scripts %r" % (tree_only,)
    assert pyproject.get("build-system", {}).get("build-backend") == "setuptools.build_meta", "pyproject.toml: build backend %r" % pyproject.get("build-system", {}).get("build-backend")

    imports = third_party_imports(package_dir)
    for module, (extra, where) in OPTIONAL_IMPORTS.items():
        if module in imports:
            assert imports[module] <= where, "%s is imported by %s, only %s may" % (module, sorted(imports[module]), where)
            wanted = [requirement_name(r).lower() for r in project.get("optional-dependencies", {}).get(extra, [])]
            assert DISTRIBUTIONS[module].lower() in wanted, "[project.optional-dependencies] %s: %r" % (extra, wanted)
            del imports[module]
    unknown = sorted(set(imports) - set(DISTRIBUTIONS))
    declared = sorted(requirement_name(r).lower() for r in project.get("dependencies", []))
    imported = sorted(DISTRIBUTIONS[m].lower() for m in imports if m in DISTRIBUTIONS)
    assert (not unknown and declared == imported), ("dependencies declared %s = distributions of the third-party imports %s%s"
                 % (declared, imported, "; imports without a known distribution: %s (in %s)"
                    % (unknown, {m: sorted(imports[m]) for m in unknown}) if unknown else ""))

    files = [os.path.join(package_dir, n) for n in package_modules(package_dir)]
    files += [os.path.join(python_dir, "pyproject.toml")] + [os.path.join(args.tools, t) for t in
                                                             list(SCRIPTS) + list(SOURCE_TREE_SCRIPTS)]
    missing_header = [os.path.relpath(p, os.path.dirname(python_dir)) for p in files
                      if "SPDX-License-Identifier: AGPL-3.0-or-later" not in "".join(open(p).readlines()[:2])]
    assert (not missing_header), ("%d files start with the SPDX header; without it: %s"
                 % (len(files), missing_header))

    # A fresh interpreter with only python/ added: every module, the API, the version.
    modules = ["plenoptic_lf." + os.path.relpath(p, package_dir)[:-3].replace(os.sep, ".") for p in files
               if p.endswith(".py") and os.path.basename(p) not in ("__init__.py", "__main__.py")]
    probe = ("import importlib, sys; sys.path.insert(0, %r); import plenoptic_lf as p\n"
             "for m in %r: importlib.import_module(m)\n"
             "missing = [n for n in p.__all__ if not hasattr(p, n)]\n"
             "print(p.__version__, p.__file__, missing, callable(p.main))" % (python_dir, modules))
    run = subprocess.run([sys.executable, "-I", "-c", probe], capture_output=True, text=True)
    expected = "%s %s [] True" % (args.version, os.path.join(package_dir, "__init__.py"))
    assert (run.returncode == 0 and run.stdout.strip() == expected), ("with only python/ on sys.path, %d modules import and the API is complete: %r (want %r)%s"
                 % (len(modules), run.stdout.strip(), expected, " stderr: " + run.stderr[-500:] if run.stderr else ""))

    env = dict(os.environ, PYTHONPATH=python_dir)
    as_module = subprocess.run([sys.executable, "-m", "plenoptic_lf", "--help"], capture_output=True, text=True,
                               env=env, cwd=args.work)
    launcher = subprocess.run(pt.decoder(args.tools) + ["--help"],
                              capture_output=True, text=True, cwd=args.work)
    assert (as_module.returncode == 0 and launcher.returncode == 0
                 and as_module.stdout.startswith("usage: plenoptic-decode") and as_module.stdout == launcher.stdout), ("python3 -m plenoptic_lf --help (exit %d) and tools/plenoptic-decode --help (exit %d) print the "
                 "same usage" % (as_module.returncode, launcher.returncode))


def test_pip_install_into_a_venv(args):
    """pip, offline, into a throwaway venv that sees Debian's numpy, Pillow and OpenImageIO
    (skipped when python3 -m venv does not work: Debian's python3-venv is missing)."""
    python_dir = os.path.abspath(args.python)
    launcher = subprocess.run(pt.decoder(args.tools) + ["--help"], capture_output=True, text=True, cwd=args.work)
    venv = os.path.join(args.work, "venv")
    source = os.path.join(args.work, "source")
    for path in (venv, source):
        shutil.rmtree(path, ignore_errors=True)
    made = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", venv],
                          capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip("pip install check: %s -m venv failed (Debian: apt install python3-venv): %s"
                    % (sys.executable, made.stderr.strip()[-300:]))
    shutil.copytree(python_dir, source, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    pip = subprocess.run([os.path.join(venv, "bin", "python"), "-m", "pip", "install", "--no-deps",
                          "--no-build-isolation", "--no-index", "--quiet", source],
                         capture_output=True, text=True)
    assert (pip.returncode == 0), ("pip install --no-deps --no-build-isolation into a venv (exit %d) %s"
                 % (pip.returncode, pip.stderr.strip()[-500:]))
    command = os.path.join(venv, "bin", "plenoptic-decode")
    run = subprocess.run([command, "--help"], capture_output=True, text=True, cwd=args.work)
    where = subprocess.run([os.path.join(venv, "bin", "python"), "-c",
                            "import plenoptic_lf; print(plenoptic_lf.__file__)"],
                           capture_output=True, text=True, cwd=args.work)
    assert (run.returncode == 0 and run.stdout == launcher.stdout
                 and where.stdout.strip().startswith(venv + os.sep)), ("the venv's plenoptic-decode --help (exit %d) prints the usage; the package loads from %s"
                 % (run.returncode, where.stdout.strip() or where.stderr.strip()[-300:]))
    for tool in SCRIPTS:
        run = subprocess.run([os.path.join(venv, "bin", tool), "--help"], capture_output=True, text=True, cwd=args.work)
        assert run.returncode == 0 and run.stdout.startswith("usage: " + tool), (
            "the venv's %s --help (exit %d): %s" % (tool, run.returncode, run.stderr[-300:]))
    # The metadata's schema is installed with the package (a link to docs/ in the source tree).
    schema = subprocess.run([os.path.join(venv, "bin", "python"), "-c", "import plenoptic_lf.metadata as m\n"
                             "print(m.schema_path(), len(m.schema_problems({'format': 1})))"],
                            capture_output=True, text=True, cwd=args.work)
    assert schema.returncode == 0 and schema.stdout.startswith(venv + os.sep), (
        "the venv's package validates against its own copy of the schema: %r %r"
        % (schema.stdout.strip(), schema.stderr.strip()[-300:]))
    assert not os.path.islink(schema.stdout.split()[0]) and int(schema.stdout.split()[1]) > 0, schema.stdout


def test_in_tree_launchers_come_from_the_table(args):
    """tools/<tool> is source/tools/launcher.py.in filled in from python/pyproject.toml's table
    (write_launchers.py --source-tree --check), for every tool of it; its first line is
    /usr/bin/python3, not /usr/bin/env python3."""
    source = os.path.dirname(os.path.abspath(args.tools))
    writer = os.path.join(source, "source", "tools", "write_launchers.py")
    check = subprocess.run([sys.executable, writer, "--source-tree", "--check"], capture_output=True, text=True)
    assert check.returncode == 0, check.stderr
    for tool, entry in list(SCRIPTS.items()) + list(SOURCE_TREE_SCRIPTS.items()):
        with open(os.path.join(args.tools, tool)) as f:
            text = f.read()
        module, function = entry.split(":")
        assert text.startswith("#!/usr/bin/python3\n") and "from %s import %s " % (module, function) in text, (
            "tools/%s: first line %r, runs %s" % (tool, text.splitlines()[0], entry))


@pytest.mark.parametrize("tool", list(SCRIPTS) + list(SOURCE_TREE_SCRIPTS))
def test_in_tree_launcher_ignores_the_python_on_path(args, tool):
    """With a python3 that lacks numpy first on PATH, tools/<tool> --help still runs (under
    /usr/bin/python3); the PATH's python3 does lack numpy (a control), and so does the launcher run
    by it explicitly, which says so in one line."""
    if not os.access("/usr/bin/python3", os.X_OK):
        pytest.skip("no /usr/bin/python3")
    folder = os.path.join(args.work, "no_numpy_bin")
    os.makedirs(folder, exist_ok=True)
    fake = os.path.join(folder, "python3")
    with open(fake, "w") as f:
        f.write(NO_NUMPY_PYTHON)
    os.chmod(fake, 0o755)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PATH"] = folder + os.pathsep + os.environ.get("PATH", "/usr/bin:/bin")
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    control = subprocess.run(["python3", "-c", "import numpy"], capture_output=True, text=True, env=env)
    assert control.returncode != 0 and "numpy" in control.stderr, "the python3 first on PATH lacks numpy (control)"
    launcher = os.path.join(args.tools, tool)
    run = subprocess.run([launcher, "--help"], capture_output=True, text=True, env=env, cwd=args.work, timeout=120)
    assert run.returncode == 0 and run.stdout.startswith("usage:"), (
        "tools/%s --help with a python3 without numpy first on PATH: exit %d, %r"
        % (tool, run.returncode, (run.stdout[:80] + run.stderr[-400:])))
    by_fake = subprocess.run(["python3", launcher, "--help"], capture_output=True, text=True, env=env, cwd=args.work)
    lines = [l for l in by_fake.stderr.splitlines() if l.strip()]
    assert (by_fake.returncode == 1 and len(lines) == 1 and lines[0].startswith(tool + ": error: this Python")
            and "lacks numpy" in lines[0] and "python3-numpy" in lines[0]), (
        "python3 tools/%s under a python3 without numpy: exit %d, %r" % (tool, by_fake.returncode, by_fake.stderr[-400:]))

