#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Write the launchers of the Python tools from their one table, python/pyproject.toml.

The table: [project.scripts] (the tools pip installs as console scripts and `cmake --install`
installs as P/bin/<tool>) and [tool.plenoptic.source-tree-scripts] (tools of the source tree
only, whose packages are not installed). Every launcher is source/tools/launcher.py.in filled in
with the tool's name and entry point, the Python it runs under (its first line: that Python, not
`/usr/bin/env python3`, so that the Python first on PATH does not matter) and where its package
is, relative to the launcher's own directory's parent.

    write_launchers.py --out DIR --python PYTHON [--packages REL]
        one launcher per tool of [project.scripts] into DIR (for `cmake --install`: PYTHON is the
        Python the build found, REL lib/python3/dist-packages); prints their names, one a line
    write_launchers.py --source-tree [--check]
        tools/<tool> for every tool of both tables, for /usr/bin/python3 and python/; --check
        compares instead of writing and exits 1 naming each launcher that differs
"""
import argparse
import os
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
PYPROJECT = os.path.join(SOURCE, "python", "pyproject.toml")
TEMPLATE = os.path.join(HERE, "launcher.py.in")
SOURCE_TREE_PYTHON = "/usr/bin/python3"


def tools(pyproject=PYPROJECT):
    """{name: (module, function, installed)} from the table, in its order."""
    with open(pyproject, "rb") as f:
        data = tomllib.load(f)
    out = {}
    tables = [(data.get("project", {}).get("scripts", {}), True),
              (data.get("tool", {}).get("plenoptic", {}).get("source-tree-scripts", {}), False)]
    for table, installed in tables:
        for name, entry in table.items():
            module, _, function = entry.partition(":")
            if not (module and function.isidentifier() and name not in out):
                raise SystemExit("write_launchers: %s: bad or repeated entry %s = %r (want \"module:function\")"
                                 % (pyproject, name, entry))
            out[name] = (module, function, installed)
    return out


def launcher(name, module, function, python, packages, where):
    """The launcher's text: the template filled in."""
    with open(TEMPLATE) as f:
        text = f.read()
    path = ", ".join(repr(part) for part in packages.split("/"))
    for key, value in (("@PYTHON@", python), ("@NAME@", name), ("@MODULE@", module), ("@FUNCTION@", function),
                       ("@PACKAGES_PATH@", path), ("@PACKAGES@", "../" + packages), ("@WHERE@", where)):
        text = text.replace(key, value)
    return text


def main(argv=None):
    p = argparse.ArgumentParser(prog="write_launchers.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--out", help="folder for the launchers of [project.scripts]")
    p.add_argument("--python", help="the Python they run under")
    p.add_argument("--packages", default="lib/python3/dist-packages",
                   help="where the packages are, relative to the launchers' folder's parent")
    p.add_argument("--source-tree", action="store_true", help="write tools/<tool> for both tables")
    p.add_argument("--check", action="store_true", help="with --source-tree: compare, do not write")
    args = p.parse_args(argv)
    table = tools()
    if args.source_tree:
        differ = []
        for name, (module, function, _) in table.items():
            path = os.path.join(SOURCE, "tools", name)
            text = launcher(name, module, function, SOURCE_TREE_PYTHON, "python", "in-tree")
            if args.check:
                try:
                    with open(path) as f:
                        same = f.read() == text and os.access(path, os.X_OK)
                except OSError:
                    same = False
                if not same:
                    differ.append(path)
                continue
            with open(path, "w") as f:
                f.write(text)
            os.chmod(path, 0o755)
        if differ:
            print("write_launchers: %s differ%s from python/pyproject.toml's table and source/tools/launcher.py.in "
                  "(or are not executable): run /usr/bin/python3 source/tools/write_launchers.py --source-tree"
                  % (", ".join(differ), "s" if len(differ) == 1 else ""), file=sys.stderr)
            return 1
        return 0
    if not (args.out and args.python):
        p.error("give --out and --python (or --source-tree)")
    os.makedirs(args.out, exist_ok=True)
    for name, (module, function, installed) in table.items():
        if not installed:
            continue
        path = os.path.join(args.out, name)
        with open(path, "w") as f:
            f.write(launcher(name, module, function, args.python, args.packages, "installed"))
        os.chmod(path, 0o755)
        print(name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
