# SPDX-License-Identifier: AGPL-3.0-or-later
"""Light fields from raw plenoptic renders: the library behind plenoptic-decode, plenoptic-targets
and plenoptic-dataset (the commands of python/pyproject.toml's [project.scripts]).

A plenoptic render (camera { plenoptic ... }) writes a raw lenslet image and, beside it,
<stem>.plenoptic.json (docs/metadata.md) with the microimage-centre lattice. This package
samples every microimage on a regular grid of (u, v) offsets around its centre and arranges
the samples as a 4-D light field L[t, s, v, u, c] (lens row and column, angular row and column,
colour; see lightfield.py), from which it computes sub-aperture views, refocusing by
shift-and-add and epipolar-plane images. It uses numpy, OpenImageIO (required: it reads every raw
image and honours the file's own encoding, e.g. a linear 16-bit PNG) and Pillow (pictures out).

    import plenoptic_lf as plf
    raw = plf.read_raw("scene.png")                       # linear float (H, W, 3)
    meta = plf.load_metadata("scene.plenoptic.json", (raw.shape[1], raw.shape[0]))
    lf = plf.decode(raw, meta)                            # lf.data is L[t, s, v, u, c]

Modules: metadata (the one metadata reader: strict JSON validated against the schema, typed
fields), images (the one image reader, OpenImageIO's ImageInput; pictures out), povray (the one
way to run POV-Ray), lightfield (raw + metadata -> LightField, views, EPI, refocus), focus (the
refocus sweep), projection (forward projection through plenoptic-project), hci (the HCI
benchmark's layout with ground truth), total_focus (a focused raw's all-in-focus image),
contact_sheet, outputs (the decoder's output folder), progress, errors, cli (the plenoptic-decode
command), targets (plenoptic-targets), dataset (plenoptic-dataset), export (plenoptic-export: other
tools' formats, docs/export/README.md), calibration (the source tree's calibration-loop: OpenCV
on the central views, docs/calibration-loop.md; imported on its own, not here). The public API carries type
hints (checked with mypy by the tests; py.typed marks the package as typed).

Importable with only its parent directory on sys.path: nothing here is generated at build time.
"""

__version__ = "0.1.0"

from .cli import main, parse_slopes
from .contact_sheet import contact_sheet
from .errors import DecodeError, DependencyError, MetadataError
from .focus import (box3, default_slopes, distance_to_slope, gray, laplacian_energy, pick_epi_row,
                    pick_near_far, sharpest_slope_map, slopes_from_depth_map)
from .images import (ImageFile, ImageReadError, RawInfo, bilinear, check_encoding, inspect_raw, linear_to_srgb,
                     read_depth_map, read_image, read_raw, read_raw_image, read_stored, require_openimageio, save_png,
                     scaled_pil_image, srgb_to_linear, to_8bit, to_linear)
from .hci import HciGeometry, export_hci, write_pfm
from .total_focus import total_focus
from .lightfield import LIGHT_FIELD_LIMIT_BYTES, DecodePlan, LightField, angular_grid, decode, mosaic, plan_decode
from .metadata import (METADATA_FORMAT, METADATA_VERSION, CameraFrame, MainLens, Metadata, MicroimagesFile,
                       MicrolensArray, RenderMetadata, WhiteImage, load_metadata, metadata_path_for, read_document,
                       read_metadata, schema_problems)
from .povray import PovrayRun, povray_command, run_povray
from .outputs import write_outputs
from .progress import Progress
from .projection import find_project_tool, project_points

__all__ = [
    "__version__",
    # metadata
    "METADATA_FORMAT", "METADATA_VERSION", "Metadata", "MetadataError", "load_metadata", "metadata_path_for",
    "RenderMetadata", "read_metadata", "read_document", "schema_problems", "CameraFrame", "MainLens",
    "MicrolensArray", "WhiteImage", "MicroimagesFile",
    # images
    "DecodeError", "DependencyError", "read_raw", "read_raw_image", "inspect_raw", "RawInfo", "check_encoding",
    "require_openimageio", "read_depth_map", "save_png", "to_8bit", "srgb_to_linear", "linear_to_srgb", "to_linear",
    "bilinear", "scaled_pil_image", "read_image", "read_stored", "ImageFile", "ImageReadError",
    # running POV-Ray
    "run_povray", "povray_command", "PovrayRun",
    # light field
    "LightField", "decode", "plan_decode", "DecodePlan", "LIGHT_FIELD_LIMIT_BYTES", "angular_grid", "mosaic",
    # refocus sweep
    "default_slopes", "slopes_from_depth_map", "distance_to_slope", "gray", "box3", "laplacian_energy",
    "sharpest_slope_map", "pick_near_far", "pick_epi_row",
    # forward projection
    "find_project_tool", "project_points",
    # ground-truth exports
    "HciGeometry", "export_hci", "write_pfm", "total_focus",
    # pictures and the command
    "contact_sheet", "write_outputs", "Progress", "parse_slopes", "main",
]
