# SPDX-License-Identifier: AGPL-3.0-or-later
"""Forward projection (world point -> pixel positions) through the compiled plenoptic-project."""

from __future__ import annotations

import os
import subprocess
from typing import Sequence


def _install_prefix_bin(package_dir):
    """PREFIX/bin when the package sits in PREFIX/lib*/python3*/{dist,site}-packages/, else None."""
    site_dir = os.path.dirname(package_dir)
    python_dir = os.path.dirname(site_dir)
    lib_dir = os.path.dirname(python_dir)
    if (os.path.basename(site_dir) in ("dist-packages", "site-packages")
            and os.path.basename(python_dir).startswith("python")
            and os.path.basename(lib_dir).startswith("lib")):
        return os.path.join(os.path.dirname(lib_dir), "bin")
    return None


def find_project_tool() -> str:
    """Path of plenoptic-project: $PLENOPTIC_PROJECT, beside this package, in the bin/ of the
    prefix the package is installed in (PREFIX/lib/python3/dist-packages/plenoptic_lf ->
    PREFIX/bin), or on PATH."""
    env = os.environ.get("PLENOPTIC_PROJECT")
    if env:
        return env
    package_dir = os.path.dirname(os.path.abspath(__file__))
    candidates = [os.path.join(package_dir, "plenoptic-project")]
    prefix_bin = _install_prefix_bin(package_dir)
    if prefix_bin:
        candidates.append(os.path.join(prefix_bin, "plenoptic-project"))
    for candidate in candidates:
        if os.access(candidate, os.X_OK):
            return candidate
    return "plenoptic-project"


def project_points(metadata_path: str, points: Sequence[Sequence[float]], tool: str | None = None,
                   blur: bool = False) -> list[tuple[int | float, ...]]:
    """World points (scene units, N x 3) -> list of (point_index, lens_k, lens_l, u, v), one per
    image of each point, by running plenoptic-project; with blur, each tuple also holds the
    image's signed blur radius in pixels (plenoptic-project --blur). Raises RuntimeError with its
    message."""
    tool = tool or find_project_tool()
    text = "\n".join("%.17g %.17g %.17g" % tuple(p) for p in points) + "\n"
    run = subprocess.run([tool] + (["--blur"] if blur else []) + [metadata_path, "-"], input=text,
                         capture_output=True, text=True)
    if run.returncode != 0:
        raise RuntimeError(run.stderr.strip() or "plenoptic-project failed with status %d" % run.returncode)
    hits = []
    for line in run.stdout.splitlines():
        words = line.split()
        hit = (int(words[0]), int(words[1]), int(words[2]), float(words[3]), float(words[4]))
        hits.append(hit + (float(words[5]),) if blur else hit)
    return hits
