# SPDX-License-Identifier: AGPL-3.0-or-later
"""Reading and checking a render's <stem>.plenoptic.json (docs/metadata.md): the one reader of
the metadata for every tool of this package and for the tests' helper.

A file is read strictly (UTF-8 only, no key twice in one object, no lone surrogate escape, no NaN
or Infinity) and validated against the metadata's JSON Schema (docs/metadata.schema.json, beside
this module as metadata.schema.json) with the jsonschema package:

    read_document(path)          the validated JSON document (a dict)
    read_metadata(path)          a RenderMetadata: typed fields of any plenoptic render
    load_metadata(path, size)    a Metadata: a RenderMetadata checked for decoding a light field
                                 (an array and its microimage lattice), with the decoder's own
                                 messages naming each wrong field

Conventions: pixel coordinates are continuous, 0-based, the centre of pixel (column i, row j)
at (i, j). Lens indices in the metadata lattice are skew indices:
centre(k, l) = origin + k a + l b.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import numpy as np
import numpy.typing as npt

from .errors import DecodeError, DependencyError, MetadataError

METADATA_FORMAT = "povray-plenoptic-metadata"
METADATA_VERSION = 1
SCHEMA_FILE = "metadata.schema.json"
MISSING_JSONSCHEMA = ("Python's jsonschema is not installed; every metadata file is validated against its JSON Schema "
                      "with it: on Debian 'apt install python3-jsonschema', with pip 'pip install jsonschema'")

Vector2 = tuple[float, float]
Vector3 = tuple[float, float, float]


def _field_at(data, path):
    """The value at a dotted path, or MetadataError naming the first missing part."""
    node = data
    walked = []
    for part in path.split("."):
        walked.append(part)
        if not isinstance(node, dict) or part not in node:
            raise MetadataError("field '%s' is missing" % ".".join(walked))
        node = node[part]
    return node


def _describe(value):
    """What a JSON value is, for error messages ("the string 'x'", "an array of 2 items"...)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "the number %r" % value
    if isinstance(value, str):
        return "the string %r" % value
    if isinstance(value, list):
        return "an array of %d items" % len(value)
    return "an object"


def _is_finite_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _checked_number(data, path, positive=False):
    """The finite (or positive) number at a dotted path, as float."""
    value = _field_at(data, path)
    if not _is_finite_number(value) or (positive and not value > 0):
        raise MetadataError("field '%s' must be a %s number, found %s"
                            % (path, "positive" if positive else "finite", _describe(value)))
    return float(value)


def _checked_numbers(data, path, count, positive=False):
    """The array of `count` finite (or positive) numbers at a dotted path, as a numpy array."""
    value = _field_at(data, path)
    if not isinstance(value, list) or len(value) != count:
        raise MetadataError("field '%s' must be an array of %d numbers, found %s"
                            % (path, count, _describe(value)))
    for i, item in enumerate(value):
        if not _is_finite_number(item) or (positive and not item > 0):
            raise MetadataError("field '%s[%d]' must be a %s number, found %s"
                                % (path, i, "positive" if positive else "finite", _describe(item)))
    return np.array(value, dtype=float)


def _optional_number(data, path):
    """The finite number at a dotted path as float, or None when it is missing or not one."""
    try:
        value = _field_at(data, path)
    except MetadataError:
        return None
    return float(value) if _is_finite_number(value) else None


MAIN_LENS_TYPES = ("thin_lens", "thick_lens", "prescription", "pinhole", "none")
# Real main lenses (docs/real-lenses.md): the paraxial equivalent (thick_lens, whose microimage
# lattice is exact) and the traced prescription (whose microimage centres leave the lattice).
REAL_LENS_TYPES = ("thick_lens", "prescription")
# main_lens.paraxial's members: finite numbers, length_mm not negative, the others positive.
PARAXIAL_FIELDS = ("back_focal_distance_mm", "front_focal_distance_mm", "front_vertex_z_mm",
                   "front_principal_plane_z_mm", "rear_principal_plane_z_mm", "entrance_pupil_z_mm",
                   "exit_pupil_z_mm")
PARAXIAL_POSITIVE = ("effective_focal_length_mm", "entrance_pupil_diameter_mm",
                     "exit_pupil_diameter_mm", "f_number", "working_f_number")


def _member(data: Any, key: str) -> Any:
    """data[key] when data is an object that has it, else None (a garbled file reads as absent)."""
    return data.get(key) if isinstance(data, dict) else None


def _float_or_none(value: Any) -> float | None:
    return float(value) if _is_finite_number(value) else None


def _float_or_nan(value: Any) -> float:
    return float(value) if _is_finite_number(value) else math.nan


def _vector(value: Any, count: int, default: float = 0.0) -> list[float]:
    """`count` finite numbers; `default` for each one missing or garbled."""
    items = value if isinstance(value, list) else []
    return [float(items[i]) if i < len(items) and _is_finite_number(items[i]) else default for i in range(count)]


def _vector2(value: Any, default: float = 0.0) -> Vector2:
    x, y = _vector(value, 2, default)
    return x, y


def _vector3(value: Any, default: float = 0.0) -> Vector3:
    x, y, z = _vector(value, 3, default)
    return x, y, z


@dataclass(frozen=True)
class CameraFrame:
    """camera_frame: the camera's placement in the world (scene units), its unit vectors."""
    location: Vector3
    right: Vector3
    up: Vector3
    direction: Vector3

    @classmethod
    def from_json(cls, frame: Any) -> CameraFrame:
        def v(key: str, default: Vector3) -> Vector3:
            given = _member(frame, key)
            return _vector3(given) if isinstance(given, list) else default
        return cls(v("location", (0.0, 0.0, 0.0)), v("right", (1.0, 0.0, 0.0)), v("up", (0.0, 1.0, 0.0)),
                   v("direction", (0.0, 0.0, 1.0)))


@dataclass(frozen=True)
class MainLens:
    """main_lens: its type (MAIN_LENS_TYPES), focal length, aperture and f-number (None for
    pinhole and none), whether it is distorted, its prescription's lens file and row count (thick
    lens and prescription; None otherwise, lens_file None for an inline prescription) and the
    front vertex's z (mm, the optics frame; 0 but for a real lens)."""
    type: str
    focal_length_mm: float | None
    aperture_mm: float | None
    f_number: float | None
    distorted: bool
    lens_file: str | None
    surface_count: int | None
    front_vertex_z_mm: float

    @classmethod
    def from_json(cls, lens: Any) -> MainLens:
        prescription = _member(lens, "prescription")
        surfaces = _member(prescription, "surfaces")
        lens_file = _member(prescription, "lens_file")
        kind = _member(lens, "type")
        return cls(type=kind if isinstance(kind, str) else "none",
                   focal_length_mm=_float_or_none(_member(lens, "focal_length_mm")),
                   aperture_mm=_float_or_none(_member(lens, "aperture_mm")),
                   f_number=_float_or_none(_member(lens, "f_number")),
                   distorted=_member(lens, "distortion") is not None,
                   lens_file=lens_file if isinstance(lens_file, str) and lens_file else None,
                   surface_count=len(surfaces) if isinstance(surfaces, list) else None,
                   front_vertex_z_mm=(_float_or_none(_member(_member(lens, "paraxial"), "front_vertex_z_mm")) or 0.0
                                      if kind in REAL_LENS_TYPES else 0.0))


@dataclass(frozen=True)
class MicrolensArray:
    """microlens_array: grid ('hexagonal' | 'rectangular'), lens ('thin_lens' | 'pinhole'), the
    focal length of each lens type (mm; empty for pinholes), pitch and distance to the sensor
    (mm; NaN in a file that garbles them), and its pose (rotate, degrees; translate, mm)."""
    grid: str
    lens: str
    focal_lengths_mm: tuple[float, ...]
    pitch_mm: float
    distance_mm: float
    rotate_deg: Vector3
    translate_mm: Vector3

    @classmethod
    def from_json(cls, array: Any) -> MicrolensArray | None:
        if not isinstance(array, dict):
            return None
        focal = array.get("focal_lengths_mm")
        grid, lens = array.get("grid"), array.get("lens")
        return cls(grid=grid if isinstance(grid, str) else "", lens=lens if isinstance(lens, str) else "",
                   focal_lengths_mm=tuple(float(f) for f in focal if _is_finite_number(f)) if isinstance(focal, list)
                   else (),
                   pitch_mm=_float_or_nan(array.get("pitch_mm")), distance_mm=_float_or_nan(array.get("distance_mm")),
                   rotate_deg=_vector3(array.get("rotate_deg")), translate_mm=_vector3(array.get("translate_mm")))


@dataclass(frozen=True)
class WhiteImage:
    """One entry of white_images: the file (beside the metadata), its values ('linear' or 'dn'),
    its scale (stored value x scale = irradiance; 1 when the entry gives none) and the f-number
    it was rendered at (None: the camera's)."""
    file: str
    values: str | None
    scale: float
    f_number: float | None
    raw_scale: Any  # the entry's scale as written, for messages about a garbled one

    @classmethod
    def list_from_json(cls, entries: Any) -> list[WhiteImage]:
        out = []
        for entry in entries if isinstance(entries, list) else []:
            if not isinstance(entry, dict) or not isinstance(entry.get("file"), str):
                continue
            values = entry.get("values")
            raw_scale = entry.get("scale", 1)
            try:
                scale = float(raw_scale)
            except (TypeError, ValueError):
                scale = float("nan")
            out.append(cls(entry["file"], values if isinstance(values, str) else None, scale,
                           _float_or_none(entry.get("f_number")), raw_scale))
        return out


@dataclass(frozen=True)
class MicroimagesFile:
    """microimages: the file of measured microimage centres (beside the metadata; None when the
    render wrote none), how many lenses it lists, and the lattice fitted to its centres as
    (origin, a, b) in pixels (None: fewer than three lit lenses, or none written)."""
    file: str | None
    lenses: int | None
    lattice_fit: tuple[np.ndarray, np.ndarray, np.ndarray] | None

    @classmethod
    def from_json(cls, entry: Any) -> MicroimagesFile:
        name = _member(entry, "file")
        lenses = _member(entry, "lenses")
        fit = _member(entry, "lattice_fit")
        lattice_fit = None
        if isinstance(fit, dict):
            try:
                origin = np.array(fit["origin_px"], dtype=float)
                basis = np.array(fit["basis_px"], dtype=float)
            except (KeyError, TypeError, ValueError):
                origin = basis = np.zeros(0)
            if (origin.shape == (2,) and basis.shape == (2, 2) and np.isfinite(origin).all()
                    and np.isfinite(basis).all()):
                lattice_fit = (origin, basis[0], basis[1])
        return cls(name if isinstance(name, str) and name else None,
                   lenses if isinstance(lenses, int) and not isinstance(lenses, bool) else None, lattice_fit)


class RenderMetadata:
    """The typed fields of a plenoptic render's metadata that this package's tools use; `raw`
    holds the whole document. Built from a document the schema accepted (read_metadata); built
    from any other, a garbled field reads as absent (None) instead of raising.

    path, raw; width, height (pixels); mm_per_unit; pixel_size_mm (x, y); principal_point_px;
    camera_frame; main_lens; array (None without a microlens array); read_out (sensor.read_out,
    the sensor chain's read-out as an object, or None); radiometry_model ('flat' | 'irradiance')
    and projected_solid_angle_sr; diffraction (whether the render applied it); white_images;
    microimages."""

    path: str
    raw: dict[str, Any]
    width: int
    height: int
    mm_per_unit: float
    pixel_size_mm: np.ndarray
    camera_frame: CameraFrame
    main_lens: MainLens
    array: MicrolensArray | None
    read_out: dict[str, Any] | None
    radiometry_model: str | None
    projected_solid_angle_sr: float | None
    diffraction: bool
    principal_point_px: Vector2 | None
    white_images: list[WhiteImage]
    microimages: MicroimagesFile

    def __init__(self, raw: dict[str, Any], path: str = "<metadata>") -> None:
        self.path = path
        self.raw = raw
        image, sensor = _member(raw, "image"), _member(raw, "sensor")
        width, height = _member(image, "width"), _member(image, "height")
        self.width = width if isinstance(width, int) else 0
        self.height = height if isinstance(height, int) else 0
        self.mm_per_unit = _float_or_none(_member(raw, "mm_per_unit")) or 1.0
        self.pixel_size_mm = np.array(_vector(_member(sensor, "pixel_size_mm"), 2, 1.0))
        self._read_records(raw)

    def _read_records(self, raw: Any) -> None:
        self.camera_frame = CameraFrame.from_json(_member(raw, "camera_frame"))
        self.main_lens = MainLens.from_json(_member(raw, "main_lens"))
        self.array = MicrolensArray.from_json(_member(raw, "microlens_array"))
        sensor = _member(raw, "sensor")
        read_out = _member(sensor, "read_out")
        self.read_out = read_out if isinstance(read_out, dict) else None
        radiometry = _member(sensor, "radiometry")
        model = _member(radiometry, "model")
        self.radiometry_model = model if isinstance(model, str) else None
        self.projected_solid_angle_sr = _float_or_none(_member(radiometry, "projected_solid_angle_sr"))
        self.diffraction = _member(raw, "diffraction") is not None
        point = _member(raw, "principal_point_px")
        self.principal_point_px = _vector2(point) if isinstance(point, list) else None
        self.white_images = WhiteImage.list_from_json(_member(raw, "white_images"))
        self.microimages = MicroimagesFile.from_json(_member(raw, "microimages"))

    def white_image(self, file_name: str) -> WhiteImage | None:
        """The white_images entry of this file name (its base name), or None."""
        for entry in self.white_images:
            if entry.file == os.path.basename(file_name):
                return entry
        return None

    def sidecar_path(self, field: str) -> str | None:
        """The file a top-level field names (depth_map, virtual_depth_map, ...), beside the
        metadata file; None when the field names none (the render did not write it)."""
        name = self.raw.get(field)
        if not isinstance(name, str):
            return None
        return os.path.join(os.path.dirname(os.path.abspath(self.path)), name)


class Metadata(RenderMetadata):
    """The fields of a render's metadata that decoding needs, checked (each wrong one named in a
    MetadataError), on top of RenderMetadata's.

    Attributes: origin, a, b (numpy 2-vectors, pixels), grid ('hexagonal' | 'rectangular'),
    diameter_px (or None), and the optics (main lens and array distances, the paraxial lens) for
    depth labels; array is never None here.
    """

    array: MicrolensArray
    grid: str
    origin: np.ndarray
    a: np.ndarray
    b: np.ndarray
    diameter_px: float | None
    main_lens_type: str
    focal_length_mm: float | None
    aperture_mm: float | None
    front_principal_z: float
    rear_principal_z: float
    entrance_pupil_z: float
    exit_pupil_z: float
    front_vertex_z: float
    entrance_pupil_mm: float | None
    exit_pupil_mm: float | None
    pitch_mm: float
    main_distance_mm: float
    array_distance_mm: float
    microimages_file: str | None

    def __init__(self, raw: dict[str, Any], path: str = "<metadata>") -> None:
        self.path = path
        self.raw = raw
        if not isinstance(raw, dict):
            raise MetadataError("the file must hold a JSON object, found %s" % _describe(raw))
        format_name = _field_at(raw, "format")
        if format_name != METADATA_FORMAT:
            raise MetadataError("field 'format' must be %r, found %s" % (METADATA_FORMAT, _describe(format_name)))
        version = _field_at(raw, "version")
        if version != METADATA_VERSION or isinstance(version, bool):
            raise MetadataError("field 'version' must be %d (the version this tool reads), found %s"
                                % (METADATA_VERSION, _describe(version)))
        for key in ("width", "height"):
            value = _field_at(raw, "image." + key)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise MetadataError("field 'image.%s' must be a positive whole number, found %s"
                                    % (key, _describe(value)))
        self.width = int(raw["image"]["width"])
        self.height = int(raw["image"]["height"])
        self.pixel_size_mm = _checked_numbers(raw, "sensor.pixel_size_mm", 2, positive=True)

        array = _field_at(raw, "microlens_array")
        lattice = _field_at(raw, "microimage_lattice")
        if array is None or lattice is None:
            raise MetadataError("fields 'microlens_array' and 'microimage_lattice' are null: the render has "
                                "no microlens array, so there is no light field to decode")
        if not isinstance(array, dict):
            raise MetadataError("field 'microlens_array' must be an object, found %s" % _describe(array))
        if not isinstance(lattice, dict):
            raise MetadataError("field 'microimage_lattice' must be an object, found %s" % _describe(lattice))
        grid = _field_at(raw, "microlens_array.grid")
        if grid not in ("hexagonal", "rectangular"):
            raise MetadataError("field 'microlens_array.grid' must be \"hexagonal\" or \"rectangular\", found %s"
                                % _describe(grid))
        self.grid = grid
        self.origin = _checked_numbers(raw, "microimage_lattice.origin_px", 2)
        basis = _field_at(raw, "microimage_lattice.basis_px")
        if (not isinstance(basis, list) or len(basis) != 2
                or not all(isinstance(v, list) and len(v) == 2 and all(_is_finite_number(x) for x in v)
                           for v in basis)):
            raise MetadataError("field 'microimage_lattice.basis_px' must be two pairs of finite numbers "
                                "[[ax, ay], [bx, by]], found %s" % _describe(basis))
        self.a = np.array(basis[0], dtype=float)
        self.b = np.array(basis[1], dtype=float)
        determinant = self.a[0] * self.b[1] - self.a[1] * self.b[0]
        if (not abs(determinant) > 0.1 * (np.hypot(*self.a) * np.hypot(*self.b))
                or min(np.hypot(*self.a), np.hypot(*self.b)) < 1.0):
            raise MetadataError("field 'microimage_lattice.basis_px' must hold two independent vectors of at "
                                "least a pixel, found %r" % (basis,))
        self.diameter_px = _optional_number(raw, "microimage_lattice.microimage_diameter_px")

        # The optics, for the refocus sweep's depth labels: checked like the rest, since a wrong
        # value here means a wrong file.
        self.mm_per_unit = _checked_number(raw, "mm_per_unit", positive=True)
        self.main_lens_type = _field_at(raw, "main_lens.type")
        if self.main_lens_type not in MAIN_LENS_TYPES:
            raise MetadataError("field 'main_lens.type' must be %s, found %s"
                                % (", ".join('"%s"' % t for t in MAIN_LENS_TYPES[:-1]) + ' or "%s"' % MAIN_LENS_TYPES[-1],
                                   _describe(self.main_lens_type)))
        self.focal_length_mm = None
        self.aperture_mm = None
        main_lens_to_array_mm = 0.0
        if self.main_lens_type in ("thin_lens",) + REAL_LENS_TYPES:
            self.focal_length_mm = _checked_number(raw, "main_lens.focal_length_mm", positive=True)
            self.aperture_mm = _checked_number(raw, "main_lens.aperture_mm", positive=True)
        if self.main_lens_type != "none":
            main_lens_to_array_mm = _checked_number(raw, "main_lens.distance_mm", positive=True)
        # The first-order lens in the optics frame (mm, z towards the scene): principal planes, pupils
        # and front vertex. A thin lens is all of them at z = 0 with its aperture as both pupils; a
        # real lens (thick_lens, prescription) has them in main_lens.paraxial, z from its rear vertex.
        self.front_principal_z = self.rear_principal_z = 0.0
        self.entrance_pupil_z = self.exit_pupil_z = self.front_vertex_z = 0.0
        self.entrance_pupil_mm = self.exit_pupil_mm = self.aperture_mm
        if self.main_lens_type in REAL_LENS_TYPES:
            self._read_real_lens(raw)
        self.pitch_mm = _checked_number(raw, "microlens_array.pitch_mm", positive=True)
        array_to_sensor_mm = _checked_number(raw, "microlens_array.distance_mm", positive=True)
        array_shift_z_mm = _checked_numbers(raw, "microlens_array.translate_mm", 3)[2]
        # Distances at the array centre, including the array's z translation.
        self.main_distance_mm = main_lens_to_array_mm - array_shift_z_mm
        self.array_distance_mm = array_to_sensor_mm + array_shift_z_mm
        # The measured microimage centres (<image>.microimages.csv) to use behind a traced
        # prescription: None looks them up beside the metadata (microimages.measured_centres);
        # plenoptic-decode's --microimages sets a path.
        self.microimages_file = None
        self._read_records(raw)

    def _read_real_lens(self, raw: dict[str, Any]) -> None:
        """main_lens.f_number, .prescription and .paraxial of a thick_lens or prescription, checked
        like the rest and against each other (the renderer writes them from one lens)."""
        _checked_number(raw, "main_lens.f_number", positive=True)
        prescription = _field_at(raw, "main_lens.prescription")
        surfaces = prescription.get("surfaces") if isinstance(prescription, dict) else None
        if not isinstance(surfaces, list) or not surfaces:
            raise MetadataError("field 'main_lens.prescription' must be an object whose 'surfaces' lists the lens's "
                                "rows, found %s" % _describe(prescription if not isinstance(prescription, dict)
                                                               else surfaces))
        paraxial = _field_at(raw, "main_lens.paraxial")
        if not isinstance(paraxial, dict):
            raise MetadataError("field 'main_lens.paraxial' must be an object, found %s" % _describe(paraxial))
        values = {}
        for name in PARAXIAL_FIELDS:
            values[name] = _checked_number(raw, "main_lens.paraxial." + name)
        for name in PARAXIAL_POSITIVE:
            values[name] = _checked_number(raw, "main_lens.paraxial." + name, positive=True)
        values["length_mm"] = length = _checked_number(raw, "main_lens.paraxial.length_mm")
        if length < 0:
            raise MetadataError("field 'main_lens.paraxial.length_mm' must not be negative, found %r" % length)
        efl = values["effective_focal_length_mm"]
        for path, value, expected in (
                ("main_lens.focal_length_mm", self.focal_length_mm, efl),
                ("main_lens.paraxial.front_vertex_z_mm", values["front_vertex_z_mm"], length)):
            if not math.isclose(value, expected, rel_tol=1e-9, abs_tol=1e-9):
                raise MetadataError("field '%s' is %r but the lens's paraxial data give %r: the file was edited"
                                    % (path, value, expected))
        self.front_vertex_z = length
        self.front_principal_z = values["front_principal_plane_z_mm"]
        self.rear_principal_z = values["rear_principal_plane_z_mm"]
        self.entrance_pupil_z = values["entrance_pupil_z_mm"]
        self.exit_pupil_z = values["exit_pupil_z_mm"]
        self.entrance_pupil_mm = values["entrance_pupil_diameter_mm"]
        self.exit_pupil_mm = values["exit_pupil_diameter_mm"]

    @property
    def pupil_distance_mm(self) -> float:
        """Exit pupil (a thin lens: the lens) to the array at its centre, mm: the D of the
        microimage lattice, which projects the lens centres from the exit pupil's centre."""
        return self.exit_pupil_z + self.main_distance_mm

    @property
    def lattice_is_exact(self) -> bool:
        """True when the microimage centres are the metadata lattice (every main lens but a
        traced prescription, whose pupil aberration and vignetting move them)."""
        return self.main_lens_type != "prescription"

    def required_sidecar(self, field: str, option: str, what: str, none_written: str) -> str:
        """sidecar_path(field) for an option that cannot do without the file: DecodeError
        `none_written` when the render wrote none, and one naming the path when it is missing."""
        path = self.sidecar_path(field)
        if path is None:
            raise DecodeError(none_written)
        if not os.path.exists(path):
            raise DecodeError("%s needs the render's %s %s, which does not exist" % (option, what, path))
        return path

    def centre(self, k: npt.ArrayLike, l: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Microimage centre(s) of skew lens index (k, l), pixels."""
        k = np.asarray(k, dtype=float)
        l = np.asarray(l, dtype=float)
        return (self.origin[0] + k * self.a[0] + l * self.b[0],
                self.origin[1] + k * self.a[1] + l * self.b[1])

    def all_centres(self, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Skew indices and centres of every microimage whose centre lies inside the image,
        at least `margin` pixels from its border: (k, l, u, v) arrays."""
        basis = np.column_stack([self.a, self.b])
        basis_inverse = np.linalg.inv(basis)
        corners = np.array([[0, 0], [self.width - 1, 0], [0, self.height - 1],
                            [self.width - 1, self.height - 1]], dtype=float) - self.origin
        corner_indices = corners @ basis_inverse.T
        k_range = np.arange(math.floor(corner_indices[:, 0].min()) - 1, math.ceil(corner_indices[:, 0].max()) + 2)
        l_range = np.arange(math.floor(corner_indices[:, 1].min()) - 1, math.ceil(corner_indices[:, 1].max()) + 2)
        kk, ll = np.meshgrid(k_range, l_range)
        u, v = self.centre(kk, ll)
        keep = ((u >= margin) & (u <= self.width - 1 - margin) & (v >= margin) & (v <= self.height - 1 - margin))
        return kk[keep], ll[keep], u[keep], v[keep]

    def slope_to_distance(self, kappa: float) -> float | None:
        """Scene distance (in front of the main lens, scene units) in focus for a refocus shift of
        kappa microimage-centre pixels per pixel of angular offset; inf beyond infinity; None when
        the main lens forms no image (pinhole, none).

        The chief-ray geometry of plenoptic 1.0 about the exit pupil (a pixel du off its
        microimage centre sees through the exit pupil's plane at -du s_x D'/d, D' = exit pupil to
        array), then the paraxial lens: the image point's distance behind the rear principal
        plane, the thin-lens equation with the effective focal length, the object's distance in
        front of the front principal plane. A thin lens has pupils and principal planes at its
        centre; a real lens (thick_lens, prescription) its paraxial ones, and the distance is
        measured from its front vertex (as focus_distance and the depth map are)."""
        if self.focal_length_mm is None:
            return None
        F, D, d = self.focal_length_mm, self.pupil_distance_mm, self.array_distance_mm
        denominator = 1.0 + kappa * d / (D + d)
        if denominator <= 0:
            return math.inf
        b = D / denominator  # exit pupil -> the plane imaged onto the array at this slope
        image = self.rear_principal_z - (self.exit_pupil_z - b)  # rear principal plane -> that plane
        if image <= F:
            return math.inf
        obj = image * F / (image - F)  # front principal plane -> the object plane
        return (self.front_principal_z + obj - self.front_vertex_z) / self.mm_per_unit

    def distance_to_kappa(self, distance: float) -> float | None:
        """The inverse of slope_to_distance: kappa for a scene distance (scene units in front of
        the main lens; of a real lens's front vertex); None when no real image exists."""
        if self.focal_length_mm is None:
            return None
        F, D, d = self.focal_length_mm, self.pupil_distance_mm, self.array_distance_mm
        obj = distance * self.mm_per_unit + self.front_vertex_z - self.front_principal_z
        if not obj > F:
            return None
        image = obj * F / (obj - F)
        b = self.exit_pupil_z - (self.rear_principal_z - image)
        if b == 0:
            return None
        return (D / b - 1.0) * (D + d) / d


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """object_pairs_hook: a key twice in one object is refused, as plenoptic-project refuses it
    (Python's json would keep the last value silently; docs/metadata.md, "Reading it")."""
    obj = {}
    for key, value in pairs:
        if key in obj:
            raise MetadataError("not valid JSON: duplicate key %r in one object (a key may appear only once)" % key)
        obj[key] = value
    return obj


def _refuse_lone_surrogates(value: Any) -> None:
    """Python's json decodes "\ud800" into a string that is not Unicode text: refused."""
    if isinstance(value, str):
        try:
            value.encode("utf-8")
        except UnicodeEncodeError:
            raise MetadataError("not valid JSON: a string holds a lone surrogate escape (\\ud800-\\udfff), "
                                "which encodes no character")
    elif isinstance(value, dict):
        for k, v in value.items():
            _refuse_lone_surrogates(k)
            _refuse_lone_surrogates(v)
    elif isinstance(value, list):
        for v in value:
            _refuse_lone_surrogates(v)


def parse_json(data: bytes | str) -> Any:
    """A metadata document from its bytes (or text): UTF-8 only, no key twice in one object, no
    lone surrogate escape. NaN and Infinity, which JSON does not have, parse here as Python's json
    reads them and are refused by check_finite (after the decoder's field checks, which name the
    field). MetadataError with one sentence."""
    try:
        text = data.decode("utf-8") if isinstance(data, bytes) else data
        doc = json.loads(text, object_pairs_hook=_unique_keys)
    except UnicodeDecodeError as e:
        raise MetadataError("not valid JSON: not UTF-8 text (%s)" % e.reason) from None
    except MetadataError:
        raise
    except ValueError as e:
        raise MetadataError("not valid JSON: %s" % e) from None
    _refuse_lone_surrogates(doc)
    return doc


def _non_finite(value: Any, where: str = "") -> str | None:
    """The path of the first NaN or Infinity in a document, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return where or "(top level)"
    if isinstance(value, dict):
        items: Iterable[tuple[str, Any]] = ((("%s.%s" % (where, k)) if where else k, v) for k, v in value.items())
    elif isinstance(value, list):
        items = (("%s[%d]" % (where, i), v) for i, v in enumerate(value))
    else:
        return None
    for path, item in items:
        found = _non_finite(item, path)
        if found is not None:
            return found
    return None


def check_finite(doc: Any) -> None:
    """MetadataError when the document holds NaN or Infinity (not JSON numbers), naming the field."""
    where = _non_finite(doc)
    if where is not None:
        raise MetadataError("not valid JSON: field '%s' holds a non-finite number (NaN or Infinity), which JSON "
                            "does not have" % where)


def schema_path() -> str:
    """The metadata's JSON Schema: metadata.schema.json beside this module (in the source tree a
    link to docs/metadata.schema.json; a copy where the package is installed)."""
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), SCHEMA_FILE)


_VALIDATOR: Any = None


def _validator() -> Any:
    """The Draft 2020-12 validator of the schema (built once); DependencyError without jsonschema."""
    global _VALIDATOR
    if _VALIDATOR is None:
        try:
            import jsonschema
        except ImportError as e:
            raise DependencyError(MISSING_JSONSCHEMA) from e
        with open(schema_path(), encoding="utf-8") as f:
            schema = json.load(f)
        jsonschema.Draft202012Validator.check_schema(schema)
        _VALIDATOR = jsonschema.Draft202012Validator(schema)
    return _VALIDATOR


def _where(error: Any) -> str:
    parts: list[str] = []
    for p in error.absolute_path:
        if isinstance(p, int):
            parts.append("[%d]" % p)
        else:
            parts.append(("." if parts else "") + str(p))
    return "".join(parts) or "(top level)"


def _leaves(error: Any) -> list[Any]:
    if not error.context:
        return [error]
    return [leaf for c in error.context for leaf in _leaves(c)]


def schema_problems(doc: Any) -> list[str]:
    """The schema's complaints about a document, as "field: message" strings (empty: it matches)."""
    errors = sorted(_validator().iter_errors(doc), key=lambda e: list(map(str, e.absolute_path)))
    out: list[str] = []
    for e in errors:
        # "null, or an object such that ..." (oneOf): the deepest reason of the object branch says
        # more than "is not valid under any of the given schemas".
        leaves = [l for l in _leaves(e) if not (l.validator == "type" and l.validator_value == "null")] or [e]
        deepest = max(len(l.absolute_path) for l in leaves)
        out.extend("%s: %s" % (_where(l), l.message[:200]) for l in leaves if len(l.absolute_path) == deepest)
    return out


def check_schema(doc: Any) -> None:
    """MetadataError when the document does not match the schema, naming up to five problems."""
    problems = schema_problems(doc)
    if problems:
        raise MetadataError("does not match docs/metadata.schema.json (%d problem%s): %s"
                            % (len(problems), "" if len(problems) == 1 else "s", "; ".join(problems[:5])))


def _read_bytes(path: str) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as e:
        raise MetadataError("cannot read the metadata file: %s" % (e.strerror or e)) from None


def read_document(path: str, schema: bool = True) -> dict[str, Any]:
    """The metadata file at `path` as a dict, read strictly and (by default) validated against
    the schema. MetadataError with one sentence (without the path), DependencyError without
    jsonschema."""
    doc = parse_json(_read_bytes(path))
    check_finite(doc)
    if schema:
        check_schema(doc)
    if not isinstance(doc, dict):  # the schema refuses it too
        raise MetadataError("the file must hold a JSON object, found %s" % _describe(doc))
    return doc


def read_metadata(path: str) -> RenderMetadata:
    """The typed fields of any plenoptic render's metadata file (with or without a microlens
    array), read strictly and validated against the schema. MetadataError, DependencyError."""
    return RenderMetadata(read_document(path), path)


def load_metadata(path: str, image_size: Sequence[int] | None = None) -> Metadata:
    """Reads and checks a metadata file for decoding; image_size (width, height) is compared with
    it. Strict JSON, the decoder's field checks (each naming the field), the size, then the
    schema. Raises MetadataError with one sentence naming the file's problem, DependencyError
    without jsonschema."""
    raw = parse_json(_read_bytes(path))
    meta = Metadata(raw, path)
    if image_size is not None and (meta.width, meta.height) != tuple(image_size):
        raise MetadataError("fields 'image.width' x 'image.height' are %d x %d but the raw image is %d x %d: "
                            "this metadata belongs to another render"
                            % (meta.width, meta.height, image_size[0], image_size[1]))
    check_finite(raw)
    check_schema(raw)
    return meta


def metadata_path_for(image_path: str) -> str:
    """<dir>/<stem>.plenoptic.json for <dir>/<stem>.<ext>, as the renderer names it; also for the
    files it writes beside the image, <stem>.raw.png and <stem>.white[.f<N>].png."""
    stem, _ = os.path.splitext(image_path)
    return re.sub(r"\.(raw|white(\.f[0-9.]+)?)$", "", stem) + ".plenoptic.json"
