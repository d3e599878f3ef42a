# SPDX-License-Identifier: AGPL-3.0-or-later
"""Reading and checking a render's <stem>.plenoptic.json (docs/metadata.md).

Conventions: pixel coordinates are continuous, 0-based, the centre of pixel (column i, row j)
at (i, j). Lens indices in the metadata lattice are skew indices:
centre(k, l) = origin + k a + l b.
"""

import json
import math
import os
import re

import numpy as np

from .errors import DecodeError, MetadataError

METADATA_FORMAT = "povray-plenoptic-metadata"
METADATA_VERSION = 1


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


class Metadata:
    """The fields of a render's metadata that decoding needs, checked.

    Attributes: path, raw (the parsed JSON), width, height, origin, a, b (numpy 2-vectors,
    pixels), grid ('hexagonal' | 'rectangular'), diameter_px (or None), pixel_size_mm,
    and the optics (main lens and array distances) when present, for depth labels.
    """

    def __init__(self, raw, path="<metadata>"):
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

    def _read_real_lens(self, raw):
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
    def pupil_distance_mm(self):
        """Exit pupil (a thin lens: the lens) to the array at its centre, mm: the D of the
        microimage lattice, which projects the lens centres from the exit pupil's centre."""
        return self.exit_pupil_z + self.main_distance_mm

    @property
    def lattice_is_exact(self):
        """True when the microimage centres are the metadata lattice (every main lens but a
        traced prescription, whose pupil aberration and vignetting move them)."""
        return self.main_lens_type != "prescription"

    def sidecar_path(self, field):
        """The file a top-level field names (depth_map, virtual_depth_map, ...), beside the
        metadata file; None when the field names none (the render did not write it)."""
        name = self.raw.get(field)
        if not isinstance(name, str):
            return None
        return os.path.join(os.path.dirname(os.path.abspath(self.path)), name)

    def required_sidecar(self, field, option, what, none_written):
        """sidecar_path(field) for an option that cannot do without the file: DecodeError
        `none_written` when the render wrote none, and one naming the path when it is missing."""
        path = self.sidecar_path(field)
        if path is None:
            raise DecodeError(none_written)
        if not os.path.exists(path):
            raise DecodeError("%s needs the render's %s %s, which does not exist" % (option, what, path))
        return path

    def centre(self, k, l):
        """Microimage centre(s) of skew lens index (k, l), pixels."""
        k = np.asarray(k, dtype=float)
        l = np.asarray(l, dtype=float)
        return (self.origin[0] + k * self.a[0] + l * self.b[0],
                self.origin[1] + k * self.a[1] + l * self.b[1])

    def all_centres(self, margin=0.0):
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

    def slope_to_distance(self, kappa):
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

    def distance_to_kappa(self, distance):
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


def _unique_keys(pairs):
    """object_pairs_hook: a key twice in one object is refused, as plenoptic-project refuses it
    (Python's json would keep the last value silently; docs/metadata.md, "Reading it")."""
    obj = {}
    for key, value in pairs:
        if key in obj:
            raise MetadataError("not valid JSON: duplicate key %r in one object (a key may appear only once)" % key)
        obj[key] = value
    return obj


def _refuse_lone_surrogates(value):
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


def load_metadata(path, image_size=None):
    """Reads and checks a metadata file; image_size (width, height) is compared with it.
    Raises MetadataError with one sentence naming the file's problem."""
    try:
        with open(path, "rb") as f:
            text = f.read()
    except OSError as e:
        raise MetadataError("cannot read the metadata file: %s" % (e.strerror or e))
    try:
        raw = json.loads(text.decode("utf-8"), object_pairs_hook=_unique_keys)
    except UnicodeDecodeError as e:
        raise MetadataError("not valid JSON: not UTF-8 text (%s)" % e.reason)
    except ValueError as e:
        raise MetadataError("not valid JSON: %s" % e)
    _refuse_lone_surrogates(raw)
    meta = Metadata(raw, path)
    if image_size is not None and (meta.width, meta.height) != tuple(image_size):
        raise MetadataError("fields 'image.width' x 'image.height' are %d x %d but the raw image is %d x %d: "
                            "this metadata belongs to another render"
                            % (meta.width, meta.height, image_size[0], image_size[1]))
    return meta


def metadata_path_for(image_path):
    """<dir>/<stem>.plenoptic.json for <dir>/<stem>.<ext>, as the renderer names it; also for the
    files it writes beside the image, <stem>.raw.png and <stem>.white[.f<N>].png."""
    stem, _ = os.path.splitext(image_path)
    return re.sub(r"\.(raw|white(\.f[0-9.]+)?)$", "", stem) + ".plenoptic.json"
