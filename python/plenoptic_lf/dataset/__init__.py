# SPDX-License-Identifier: AGPL-3.0-or-later
"""Data sets of plenoptic renders: a TOML spec (sweeps, seeded random draws, per-item options)
rendered item by item into a folder with a manifest, resumably, on this machine or as a Slurm
job array, whole or in row bands (docs/datasets.md). Standard library only, apart from
OpenImageIO and numpy to merge row bands."""

from .spec import Item, Spec, SpecError, load_spec
from .store import Store

__all__ = ["Item", "Spec", "SpecError", "load_spec", "Store"]
