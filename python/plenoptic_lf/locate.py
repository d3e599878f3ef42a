# SPDX-License-Identifier: AGPL-3.0-or-later
"""Where the programs beside this package are: the plenoptic renderer, plenoptic-project and
plenoptic-lens-data, in this source tree's build/, in the prefix the package is installed in, or
on PATH."""

import os
import shutil

# This file is <repository>/python/plenoptic_lf/locate.py in the source tree, and
# P/lib/python3/dist-packages/plenoptic_lf/locate.py when installed under the prefix P.
_HERE = os.path.dirname(os.path.abspath(__file__))
REPOSITORY = os.path.dirname(os.path.dirname(_HERE))
PREFIX = os.path.normpath(os.path.join(_HERE, "..", "..", "..", ".."))


def find_program(name, given, candidates, option):
    """`given`, else the first candidate that exists, else `name` on PATH; FileNotFoundError
    naming the option that gives it."""
    if given:
        # Absolute: renders run in other folders (and Slurm tasks on other nodes).
        return os.path.abspath(given) if os.sep in given else (shutil.which(given) or given)
    for candidate in candidates:
        if os.path.exists(candidate):
            return os.path.abspath(candidate)
    found = shutil.which(name)
    if not found:
        raise FileNotFoundError("cannot find %s: give its path with %s" % (name, option))
    return found


def find_povray(given=None):
    """The plenoptic renderer (never Debian's povray: it is looked for as povray-plenoptic)."""
    return find_program("povray-plenoptic", given or os.environ.get("PLENOPTIC_POVRAY"),
                        [os.path.join(REPOSITORY, "build", "povray"), os.path.join(PREFIX, "bin", "povray-plenoptic")],
                        "--povray")


def find_project(given=None):
    """plenoptic-project, the forward projection built beside the renderer."""
    return find_program("plenoptic-project", given,
                        [os.path.join(REPOSITORY, "build", "plenoptic-project"), os.path.join(PREFIX, "bin", "plenoptic-project")],
                        "--project")


def find_lens_data(given=None):
    """plenoptic-lens-data, the optics core's answers about a lens file (plenoptic-lens's optics),
    built beside the renderer."""
    return find_program("plenoptic-lens-data", given or os.environ.get("PLENOPTIC_LENS_DATA"),
                        [os.path.join(REPOSITORY, "build", "plenoptic-lens-data"),
                         os.path.join(PREFIX, "bin", "plenoptic-lens-data")],
                        "--lens-data")
