# SPDX-License-Identifier: AGPL-3.0-or-later
"""A plenoptic 1.0 render in the HCI 4D light-field benchmark's layout (docs/hci-export.md):
N x N views input_Cam000.png.. (row-major, top-left first), parameters.cfg as the benchmark's
Blender add-on writes it, and the centre view's gt_depth_lowres.pfm and gt_disp_lowres.pfm
computed from the render's depth map (the scene's geometry), not estimated.

The geometry. Behind a thin main lens (focal length F, array at D, so the plane z0 with
1/z0 + 1/D = 1/F is in focus) a pixel offset (du, dv) pixels from its microimage centre sees the
scene through the point x_a = (du, -dv) * pixel * D / d of the main lens (d: array to sensor),
and every lens's pixels look at the lens centre's conjugate on the plane z0. So each view is a
pinhole camera at x_a whose image plane is that focus plane: the benchmark's camera grid with
shifted sensors, baseline pixel * step * D / d between neighbouring views, a focal length of
D / pitch view pixels, and a disparity of

    disp = baseline * (D / pitch) * (1 / Z - 1 / z0)      (Z: depth along the axis)

view pixels per view step, positive in front of the focus plane, as the toolkit's depth2disp
computes it from parameters.cfg. A point at (x, y) in the centre view lies at
(x - disp * (j - c), y - disp * (i - c)) in view (i, j) (row i, column j, centre c).

A thick_lens (a prescription's paraxial equivalent) is the same ideal lens between its principal
planes with the exit pupil as its aperture: its views are pinhole cameras on the entrance pupil's
plane (HciGeometry). A traced prescription is refused: its views are not pinhole cameras.
"""

from __future__ import annotations

import configparser
import datetime
import math
import os

import numpy as np
import numpy.typing as npt

from .errors import DecodeError
from .images import read_depth_map, save_png
from .lightfield import angular_grid, decode, plan_decode
from .metadata import Metadata
from .progress import Progress


def write_pfm(path: str, values: npt.ArrayLike) -> None:
    """A single-channel float32 PFM (netpbm's format: 'Pf', width height, -1 for little-endian,
    rows from the bottom), as the benchmark's files are."""
    values = np.asarray(values, dtype="<f4")
    height, width = values.shape
    with open(path, "wb") as f:
        f.write(b"Pf\n%d %d\n-1\n" % (width, height))
        f.write(np.ascontiguousarray(values[::-1]).tobytes())


def check_hci_camera(meta: Metadata) -> None:
    """DecodeError unless the render's sub-aperture views form the benchmark's camera grid exactly
    (check_pinhole_views)."""
    check_pinhole_views(meta, "--hci", DecodeError)


def check_pinhole_views(meta: Metadata, who: str, error: type) -> None:
    """`error` (a message starting with `who`, the option or format asking) unless every
    sub-aperture view of the render is a pinhole camera on one grid with square pixels, which a
    disparity per pixel needs: a thin_lens or thick_lens main lens without distortion, one kind of
    thin microlens with d = f (plenoptic 1.0), an array aligned with the sensor (not turned, not
    tilted), square pixels, the array beyond the focal length, an upright exit pupil."""
    if meta.main_lens_type == "prescription":
        raise error("%s: the disparity ground truth assumes an ideal lens, whose sub-aperture views are "
                    "pinhole cameras on one grid; this render's main lens is a traced prescription, whose "
                    "distortion and pupil aberration bend each view's rays differently, so no single "
                    "disparity per pixel exists. Render the same camera with thick_lens (its paraxial "
                    "equivalent)" % who)
    if meta.main_lens_type not in ("thin_lens", "thick_lens"):
        raise error("%s needs a thin_lens or thick_lens main lens (its views are then pinhole cameras on one "
                    "grid); this render's main lens is %s" % (who, meta.main_lens_type))
    if meta.main_lens.distorted:
        raise error("%s needs a lens without distortion: a distorted lens's views are not pinhole cameras, "
                    "so no single disparity per pixel exists" % who)
    array = meta.array
    focal = array.focal_lengths_mm
    if array.lens != "thin_lens" or len(focal) != 1:
        raise error("%s needs one kind of thin microlens (plenoptic 1.0); this array has %s"
                    % (who, "pinholes" if array.lens == "pinhole" else "%d lens types" % len(focal)))
    f = focal[0]
    d = array.distance_mm
    F = meta.focal_length_mm
    assert F is not None, "a thin_lens or thick_lens has a focal length (Metadata checks it)"
    if not math.isclose(meta.array_distance_mm, f, rel_tol=1e-6):
        raise error("%s decodes plenoptic 1.0 cameras (array to sensor distance d = microlens focal length "
                    "f); this one has d = %g mm and f = %g mm, a focused (2.0) camera whose microimages are "
                    "not sub-aperture samples" % (who, d, f))
    rotate = tuple(array.rotate_deg)
    if any(abs(r) > 0 for r in rotate):
        raise error(who + " needs an array aligned with the sensor (rotate <0, 0, 0>); this one is turned "
                    "(rotate <%g, %g, %g>): its views' pixel axes are not the camera grid's axes" % rotate)
    px, py = meta.pixel_size_mm
    if not math.isclose(px, py, rel_tol=1e-9):
        raise error("%s needs square pixels (one baseline and one disparity for both axes); pixel_size is "
                    "%g x %g mm" % (who, px, py))
    D = meta.rear_principal_z + meta.main_distance_mm
    if not D > F:
        raise error("%s needs the array beyond the focal length (D = %g mm from the %s, F = %g mm): "
                    "otherwise nothing in front of the lens is in focus on it"
                    % (who, D, "lens" if meta.main_lens_type == "thin_lens" else "rear principal plane", F))
    if not HciGeometry(meta, 1.0).pupil_magnification > 0:
        raise error("%s needs a lens whose exit pupil is an upright image of its entrance pupil; this "
                    "thick lens's pupil magnification is negative, which turns its camera grid over" % who)


class HciGeometry:
    """The camera grid the views form (all lengths mm): F, D (main lens to array), d, pitch,
    pixel, step; z0 the distance in focus and baseline between neighbouring views, both at the
    views' centres of projection; focal_px the views' focal length in view pixels.

    A thin lens is its own pupils and principal planes. A thick_lens (the paraxial equivalent of
    a prescription) is the same ideal lens between its principal planes, with the exit pupil as
    its aperture: a pixel du off its microimage centre sees through the exit pupil's plane at
    du pixel D'/d (D': exit pupil to array), whose conjugate is the point of the entrance pupil's
    plane 1/m as far from the axis (m: the pupils' magnification). The views are pinhole cameras
    there, looking at the array's conjugate plane: baseline pixel step D'/(d m), focal length
    z0 s_i/(s_o pitch) view pixels (s_o, s_i: that plane's and the array's distances from the
    principal planes; z0: the plane's from the entrance pupil). For a thin lens these are
    pixel step D/d and D/pitch."""

    def __init__(self, meta: Metadata, step: float) -> None:
        F = meta.focal_length_mm
        assert F is not None, "check_hci_camera: a thin or thick lens has a focal length"
        self.F = F
        self.D = meta.main_distance_mm
        self.d = meta.array_distance_mm
        self.pitch = meta.pitch_mm
        self.pixel = meta.pixel_size_mm[0]
        self.step = float(step)
        self.pupil_distance = meta.pupil_distance_mm  # exit pupil -> array (D')
        self.image_distance = s_i = meta.rear_principal_z + meta.main_distance_mm  # rear principal plane -> array
        self.object_distance = s_o = s_i * F / (s_i - F)  # front principal plane -> the plane in focus
        # Entrance pupil -> exit pupil through the ideal lens: lateral magnification 1 / (1 - s / F),
        # s the entrance pupil's distance in front of the front principal plane.
        self.pupil_magnification = 1.0 / (1.0 - (meta.entrance_pupil_z - meta.front_principal_z) / F)
        self.pupil_z = meta.entrance_pupil_z  # the views' centres of projection lie in this plane
        self.front_principal_z = meta.front_principal_z
        self.z0 = meta.front_principal_z + s_o - meta.entrance_pupil_z
        self.baseline = self.pixel * self.step * self.pupil_distance / self.d / self.pupil_magnification
        self.focal_mm = self.z0 * s_i / s_o  # D for a thin lens
        self.focal_px = self.focal_mm / self.pitch

    def disparity(self, depth_mm: np.ndarray | float) -> np.ndarray:
        """View pixels per view step of points at depth Z (mm from the entrance pupil's plane):
        +inf depth gives the finite disparity of infinity; NaN stays NaN."""
        with np.errstate(divide="ignore"):
            inverse = np.where(np.isinf(depth_mm), 0.0, 1.0 / depth_mm)
        return self.baseline * self.focal_px * (inverse - 1.0 / self.z0)


def planar_depth_mm(meta, geometry, distance_units, pixel_u, pixel_v, centre_u, centre_v):
    """Depth along the optical axis (mm, from the entrance pupil's plane; a thin lens's own) of the
    surface the chief ray of raw pixel (pixel_u, pixel_v) meets at the depth map's distance (scene
    units, from where the ray leaves the lens: a thin lens's plane, a thick lens's front principal
    plane), for a pixel of the microimage centred at (centre_u, centre_v). The chief ray's image
    side runs through the pixel x and its lens centre c = m D'/(D' + d) (m: the microimage centre)
    to the exit pupil's plane at x' = c + (c - x) D'/d; its scene side from x' / m_p on the
    entrance pupil's plane to the lens centre's conjugate C' = -c s_o / s_i on the plane in focus.
    Positions are taken on the sensor relative to the principal point (a reflection of the optics
    frame, which leaves the ray's length unchanged). +inf stays +inf; -1 (blocked) gives NaN."""
    px, py = meta.pixel_size_mm
    pu, pv = meta.principal_point_px or (0.0, 0.0)
    D, d = geometry.pupil_distance, geometry.d
    x = np.stack([(np.asarray(pixel_u, float) - pu) * px, (np.asarray(pixel_v, float) - pv) * py])
    m = np.stack([(np.asarray(centre_u, float) - pu) * px, (np.asarray(centre_v, float) - pv) * py])
    c = m * D / (D + d)
    aperture = (c + (c - x) * D / d) / geometry.pupil_magnification
    target = -c * geometry.object_distance / geometry.image_distance
    lateral = target - aperture
    z0 = geometry.z0
    cosine = z0 / np.sqrt(lateral[0] ** 2 + lateral[1] ** 2 + z0 * z0)
    distance = np.asarray(distance_units, float)
    depth = distance * meta.mm_per_unit * cosine + (geometry.front_principal_z - geometry.pupil_z)
    return np.where(distance < 0, np.nan, depth)


def _square_grid_count(meta: Metadata, n: int | None, step: float) -> int:
    """Views per side: the largest odd N whose N x N angular samples all lie in the usable
    microimage disc, or n checked against it."""
    du, _, mask = angular_grid(meta, None, step)
    largest = 1
    centre = len(du) // 2
    for half in range(centre + 1):
        if mask[centre - half:centre + half + 1, centre - half:centre + half + 1].all():
            largest = 2 * half + 1
    if n is None:
        return largest
    if n < 1 or n % 2 == 0:
        raise DecodeError("--angular must be odd and positive for --hci, got %d" % n)
    if n > largest:
        raise DecodeError("--hci needs every view of the N x N grid inside the usable microimage disc: at "
                          "--step %g px at most %d x %d views fit, not %d x %d" % (step, largest, largest, n, n))
    return n


def _nearest_samples(meta, plan, du, dv):
    """For the samples at offset (du, dv) of every lens position (t, s) of the plan: the raw pixel
    nearest to it and the centre of the microimage it lies in (a half-shifted hexagonal row takes
    the lens k0, below the tie). Four (T, S) arrays: pixel u, v; centre u, v."""
    lens_k = plan.k0 + (plan.frac > 0.5)
    centre_u, centre_v = meta.centre(lens_k, plan.l)
    pixel_u = np.clip(np.rint(centre_u + du), 0, meta.width - 1).astype(np.intp)
    pixel_v = np.clip(np.rint(centre_v + dv), 0, meta.height - 1).astype(np.intp)
    return pixel_u, pixel_v, centre_u, centre_v


def _square_rows(meta, T):
    """Rows of a square-pixel view: (source row per output row as a float, count). A hexagonal
    grid's rows are sqrt(3)/2 lens pitches apart: the output takes rows one pitch apart."""
    if meta.grid != "hexagonal":
        return np.arange(T, dtype=float), T
    spacing = math.sqrt(3) / 2
    count = int(math.floor((T - 1) * spacing + 1e-9)) + 1
    return np.arange(count) / spacing, count


def _resample_rows(view, rows, nearest):
    """view (T, S, ...) sampled at fractional rows: linearly (colours) or at the nearest row
    (depths: every value is a surface the view sees)."""
    if nearest:
        return view[np.clip(np.rint(rows).astype(np.intp), 0, view.shape[0] - 1)]
    r0 = np.clip(np.floor(rows).astype(np.intp), 0, view.shape[0] - 1)
    r1 = np.minimum(r0 + 1, view.shape[0] - 1)
    w = (rows - r0).reshape((-1,) + (1,) * (view.ndim - 1)).astype(np.float32)
    return view[r0] * (1 - w) + view[r1] * w


def _blender_pose(meta):
    """The centre camera's place and XYZ Euler angles as the benchmark's Blender add-on writes
    them: POV-Ray's left-handed world (x, y, z) is Blender's (x, z, y); metres."""
    frame = meta.camera_frame
    to_blender = np.array([[1, 0, 0], [0, 0, 1], [0, 1, 0]], float)
    scale = meta.mm_per_unit / 1000.0
    # The centre view's centre of projection: the entrance pupil's centre (a thin lens's centre).
    direction = np.asarray(frame.direction, float)
    pupil = np.asarray(frame.location, float) + meta.entrance_pupil_z / meta.mm_per_unit * direction / np.linalg.norm(direction)
    location = to_blender @ pupil * scale

    def unit(v):
        v = to_blender @ np.asarray(v, float)
        return v / np.linalg.norm(v)

    right, up, direction = unit(frame.right), unit(frame.up), unit(frame.direction)
    # A Blender camera looks along its local -z with +y up: columns right, up, -direction.
    rotation = np.column_stack([right, up, -direction])
    # R = Rz(rz) Ry(ry) Rx(rx) (Blender's 'XYZ' order).
    ry = math.asin(-max(-1.0, min(1.0, rotation[2, 0])))
    if abs(rotation[2, 0]) < 1 - 1e-12:
        rx = math.atan2(rotation[2, 1], rotation[2, 2])
        rz = math.atan2(rotation[1, 0], rotation[0, 0])
    else:  # gimbal lock: put the whole turn about z into x
        rx = math.atan2(-rotation[1, 2], rotation[1, 1])
        rz = 0.0
    return location, (rx, ry, rz)


def _disparity_range(disparity):
    finite = disparity[np.isfinite(disparity)]
    if finite.size == 0:
        return -1.0, 1.0
    # As the add-on rounds them: outward to 0.1, widened by 0.1.
    return math.floor(finite.min() * 10) / 10 - 0.1, math.ceil(finite.max() * 10) / 10 + 0.1


def _write_parameters(path, meta, geometry, n, width, height, disp_range, scene):
    location, angles = _blender_pose(meta)
    config = configparser.ConfigParser()
    config.optionxform = str
    config["intrinsics"] = {
        "focal_length_mm": repr(geometry.focal_mm),
        "image_resolution_x_px": str(width),
        "image_resolution_y_px": str(height),
        "sensor_size_mm": repr(geometry.pitch * max(width, height)),
        "fstop": repr(geometry.d / geometry.pixel),
    }
    config["extrinsics"] = {
        "num_cams_x": str(n),
        "num_cams_y": str(n),
        "baseline_mm": repr(geometry.baseline),
        "focus_distance_m": repr(geometry.z0 / 1000.0),
        "center_cam_x_m": repr(float(location[0])),
        "center_cam_y_m": repr(float(location[1])),
        "center_cam_z_m": repr(float(location[2])),
        "center_cam_rx_rad": repr(angles[0]),
        "center_cam_ry_rad": repr(angles[1]),
        "center_cam_rz_rad": repr(angles[2]),
    }
    config["meta"] = {
        "scene": scene,
        "category": "additional",
        "date": datetime.date.today().isoformat(),
        "version": "povray-plenoptic",
        "authors": "rendered with POV-Ray's plenoptic camera, exported by plenoptic-decode --hci",
        "contact": "",
        "cycles_seed": "0",
        "disp_min": repr(disp_range[0]),
        "disp_max": repr(disp_range[1]),
        "frustum_disp_min": repr(disp_range[0]),
        "frustum_disp_max": repr(disp_range[1]),
        "depth_map_scale": "1",
    }
    # Beyond the benchmark's keys: where the views come from (a reader of the benchmark ignores it).
    config["plenoptic"] = {
        "raw_metadata": os.path.basename(meta.path),
        "grid": meta.grid,
        "angular_step_px": repr(geometry.step),
        "main_lens": meta.main_lens_type,
        "main_lens_focal_length_mm": repr(geometry.F),
        "main_lens_to_array_mm": repr(geometry.D),
        "array_to_sensor_mm": repr(geometry.d),
        "pitch_mm": repr(geometry.pitch),
        "pixel_size_mm": repr(geometry.pixel),
        "view_rows": "hexagonal rows resampled to square pixels (one pitch apart), linearly; depths nearest"
                     if meta.grid == "hexagonal" else "one lens row per view row",
        "depth": "metres along the optical axis from the main lens (a thick lens: its entrance pupil); inf where "
                 "the ray meets nothing, "
                 "nan where it was blocked",
    }
    with open(path, "w") as f:
        config.write(f)


def depth_map_path(meta: Metadata) -> str:
    """The render's depth map beside its metadata; DecodeError when the render wrote none."""
    return meta.required_sidecar("depth_map", "--hci", "depth map",
                                 "--hci computes the ground truth from the render's depth map, and this render "
                                 "wrote none: add depth_map to the camera and render again")


def export_hci(raw: np.ndarray, meta: Metadata, outdir: str, n: int | None = None, step: float = 1.0,
               all_views: bool = False, progress: Progress | None = None) -> int:
    """Writes the benchmark's layout into outdir; returns the number of views per side."""
    if progress is None:
        progress = Progress(False)
    check_hci_camera(meta)
    depth_path = depth_map_path(meta)
    n = _square_grid_count(meta, n, step)
    geometry = HciGeometry(meta, step)
    distances = read_depth_map(depth_path)
    if distances is None or distances.shape != (meta.height, meta.width):
        raise DecodeError("cannot read the depth map %s as a %d x %d image" % (depth_path, meta.width, meta.height))

    lf = decode(raw, meta, n, step, progress)
    plan = plan_decode(meta, n, step, raw.shape[2])
    T, S = lf.shape[:2]
    rows, height = _square_rows(meta, T)

    def view_depth_mm(i, j):
        pixel_u, pixel_v, centre_u, centre_v = _nearest_samples(meta, plan, lf.du[j], lf.dv[i])
        depth = planar_depth_mm(meta, geometry, distances[pixel_v, pixel_u], pixel_u, pixel_v, centre_u, centre_v)
        return _resample_rows(depth, rows, nearest=True)

    os.makedirs(outdir, exist_ok=True)
    progress.stage("writing %d x %d views of %d x %d px (HCI layout) to %s" % (n, n, S, height, outdir))
    centre = n // 2
    for i in range(n):
        for j in range(n):
            index = i * n + j
            save_png(os.path.join(outdir, "input_Cam%03d.png" % index),
                     np.clip(_resample_rows(lf.view(i, j), rows, nearest=False), 0, 1))
            if all_views:
                depth = view_depth_mm(i, j)
                write_pfm(os.path.join(outdir, "gt_depth_lowres_Cam%03d.pfm" % index), depth / 1000.0)
                write_pfm(os.path.join(outdir, "gt_disp_lowres_Cam%03d.pfm" % index), geometry.disparity(depth))
        progress.update(i + 1, n)
    depth = view_depth_mm(centre, centre)
    centre_disparity = geometry.disparity(depth)
    write_pfm(os.path.join(outdir, "gt_depth_lowres.pfm"), depth / 1000.0)
    write_pfm(os.path.join(outdir, "gt_disp_lowres.pfm"), centre_disparity)
    scene = os.path.splitext(os.path.basename(meta.path))[0]
    if scene.endswith(".plenoptic"):
        scene = scene[:-len(".plenoptic")]
    _write_parameters(os.path.join(outdir, "parameters.cfg"), meta, geometry, n, S, height,
                      _disparity_range(centre_disparity), scene)
    return n
