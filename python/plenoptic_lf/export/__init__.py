# SPDX-License-Identifier: AGPL-3.0-or-later
"""plenoptic-export: a render's image and ground truth in the layouts other tools read
(docs/export/README.md).

The shape every format shares:

    FORMATS = {name: module}     the formats this build has, each a module with
        SUMMARY                  one line: what the format is and who reads it
        OPTIONS                  {option name: help} the format accepts (`--angular`, `--step`
                                 or `-O NAME=VALUE` on the command line); values arrive as the
                                 command line converts them (angular int, step float, -O strings)
        export(render, out_dir, **options) -> list[Path]
                                 writes the format into out_dir (a fresh, empty staging folder:
                                 the command moves each file into the user's folder only when
                                 the whole export succeeded, so no half-written file is left)
                                 and returns the files written, each under out_dir

    Render                       the loaded render: paths, metadata (plenoptic_lf.metadata),
                                 the picture read lazily as the decoder reads it, the decoded
                                 light field, the depth map; progress messages

A format refuses what it cannot express with ExportError (one sentence: what, and why), never
an approximation. Nothing here needs LFToolbox, PlenopticToolbox or COMPOTE at run time.
"""

from __future__ import annotations

import os
from types import ModuleType
from typing import Any

import numpy as np

from ..errors import DecodeError
from ..images import Encoding
from ..progress import Progress


class ExportError(DecodeError):
    """The render cannot be written in the format asked for (one sentence for the user: what the
    format cannot express, and why)."""


class Render:
    """A render as the exporters see it. `image_path`: the rendered image, whose metadata sits
    beside it (<stem>.plenoptic.json, or `metadata_path`), as plenoptic-decode takes it.
    The metadata is read at once (MetadataError when it is missing or broken); the picture, the
    light field and the depth map when first asked for."""

    def __init__(self, image_path: str, metadata_path: str | None = None, encoding: Encoding = "auto",
                 progress: Progress | None = None) -> None:
        from ..images import inspect_raw
        from ..metadata import load_metadata, metadata_path_for
        self.image_path = image_path
        self.metadata_path = metadata_path or metadata_path_for(image_path)
        self.encoding = encoding
        self.progress = progress or Progress(False, "plenoptic-export")
        if not os.path.exists(image_path):
            raise DecodeError("%s: the rendered image does not exist" % image_path)
        self.info = inspect_raw(image_path, encoding)
        if not os.path.exists(self.metadata_path):
            raise ExportError("%s: the render's metadata does not exist (every plenoptic render writes "
                              "<stem>.plenoptic.json beside its image; name another with --metadata)"
                              % self.metadata_path)
        self.meta = load_metadata(self.metadata_path, (self.info.width, self.info.height))
        self._picture: np.ndarray | None = None
        self._light_fields: dict[tuple[Any, float], Any] = {}

    @property
    def stem(self) -> str:
        """The image's name without its extension (and without .raw/.white): the exports' file stem."""
        name = os.path.basename(self.metadata_path)
        return name[:-len(".plenoptic.json")] if name.endswith(".plenoptic.json") else os.path.splitext(name)[0]

    def picture(self) -> np.ndarray:
        """The picture, linear float (H, W, 3), read as plenoptic-decode reads it."""
        if self._picture is None:
            from ..cli import read_picture
            from ..images import png_layout
            from ..sensor import picture_reading
            reading = picture_reading(self.meta, self.image_path, png_layout(self.image_path), False,
                                      self.encoding != "auto")
            self.progress.stage("image %s: %s" % (os.path.basename(self.image_path), self.info.describe()))
            self._picture = read_picture(self.image_path, self.meta, self.encoding, self.progress,
                                         reading=reading, announced=True)
        return self._picture

    def light_field(self, angular: int | None = None, step: float = 1.0) -> Any:
        """The decoder's LightField (plenoptic_lf.lightfield.decode) of the picture."""
        key = (angular, float(step))
        if key not in self._light_fields:
            from ..lightfield import decode, plan_decode
            plan_decode(self.meta, angular, step)  # refuse an impossible size before reading pixels
            self._light_fields[key] = decode(self.picture(), self.meta, angular, step, self.progress)
        return self._light_fields[key]

    def depth_map_path(self, needed_by: str) -> str:
        """The render's depth map (its distances along each ray, scene units), or ExportError."""
        path = self.meta.sidecar_path("depth_map")
        if path is None:
            raise ExportError("%s needs the render's depth map (ground truth), and this render wrote none: add "
                              "depth_map to the camera and render again" % needed_by)
        if not os.path.exists(path):
            raise ExportError("%s needs the render's depth map %s, which does not exist" % (needed_by, path))
        return path

    def depth_map(self, needed_by: str) -> np.ndarray:
        from ..images import read_depth_map
        path = self.depth_map_path(needed_by)
        values = read_depth_map(path)
        if values is None or values.shape != (self.meta.height, self.meta.width):
            raise ExportError("cannot read the depth map %s as a %d x %d image" % (path, self.meta.width,
                                                                                   self.meta.height))
        return values


# The registry: one import and one entry per format, each on its own line (formats are added
# independently), sorted by name.
from . import compote  # noqa: E402
from . import eslf  # noqa: E402
from . import kiel  # noqa: E402
from . import raytrix  # noqa: E402
from . import views  # noqa: E402

FORMATS: dict[str, ModuleType] = {
    "compote": compote,
    "eslf": eslf,
    "kiel": kiel,
    "raytrix": raytrix,
    "views": views,
}

__all__ = ["FORMATS", "ExportError", "Render"]
