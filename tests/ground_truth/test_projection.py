# SPDX-License-Identifier: AGPL-3.0-or-later
"""Forward projection (plenoptic-project) against the render itself.

Small emissive spheres float at known positions in front of a turned and shifted plenoptic
camera; each shows up as a small bright blob in every microimage whose lens sees it. The
brightness centroid of every blob must sit where plenoptic-project says the sphere's centre
images, to 0.25 px, for three set-ups:

  chief-ray  thin main lens + pinhole microlenses (hexagonal): a sharp pinhole image per lens
  1.0        thin microlenses at d = f (hexagonal): spheres well off the focus plane, so each lens
             shows a small patch around the chief line through its centre
  2.0        thin microlenses at d != f (rectangular, Keplerian): spheres at the depth the
             microlenses focus onto the sensor, a sharp image per lens
  array      no main lens, pinhole microlenses (a camera array): each lens a pinhole camera

Only lenses whose whole cell lies inside the cone of light (sphere image -> main aperture) are
compared (a lens at the cone's rim sees the sphere cut off, which moves the centroid); this
choice, the thin-lens image of each sphere and the camera frame are computed here from the
specification (docs/specification.md), not by the code under test. Every other blob must still
be explained by a predicted image, and every predicted image must show a blob.
"""

import math

import numpy as np

import pytest

import plenoptic_testing as pt

TOLERANCE_PX = 0.25
W, H = 320, 240
PIXEL = 0.01

# Camera pose: turned 20 degrees about y, shifted; the metadata frame must say the same.
LOCATION = np.array([0.1, 0.2, -0.3])
TURN_DEG = 20.0
DIRECTION = np.array([math.sin(math.radians(TURN_DEG)), 0.0, math.cos(math.radians(TURN_DEG))])
RIGHT = np.array([math.cos(math.radians(TURN_DEG)), 0.0, -math.sin(math.radians(TURN_DEG))])
UP = np.array([0.0, 1.0, 0.0])
MM_PER_UNIT = 1000.0

# Where on the sensor (mm) the spheres' centre lines aim: far enough apart that their blobs
# never share a microimage.
TARGETS = [(-0.8, -0.55), (0.8, -0.55), (-0.8, 0.55), (0.8, 0.55)]

CONFIGS = [
    {
        "name": "chief-ray",
        "grid": "hexagonal", "pitch": 0.2, "micro_f": None, "d": 0.5,
        "F": 50.0, "A": 18.0, "focus_mm": 1000.0, "D": None,
        "depths_mm": [515.0, 10000.0, 540.0, 6000.0],
        "blob_px": 1.5,     # designed blob radius
        "reach_px": 2.5,    # radius within which a blob's pixels lie
    },
    {
        "name": "plenoptic-1.0",
        "grid": "hexagonal", "pitch": 0.12, "micro_f": 0.3, "d": 0.3,
        "F": 50.0, "A": 20.0, "focus_mm": 1000.0, "D": None,
        "depths_mm": [570.0, 4200.0, 600.0, 3500.0],
        "blob_px": 1.4,
        "reach_px": 4.0,
    },
    {
        "name": "focused-2.0",
        "grid": "rectangular", "pitch": 0.15, "micro_f": 0.5, "d": 0.575,
        "F": 50.0, "A": 12.5, "focus_mm": None, "D": 56.0,
        # The microlenses (f = 0.5, d = 0.575) focus a plane a = f d / (d - f) = 3.83 mm in front
        # of the array onto the sensor: main-lens image at b = D - a, object at b F / (b - F).
        "depths_mm": None,
        "blob_px": 2.0,
        "reach_px": 3.5,
    },
    {
        "name": "camera-array",
        "grid": "rectangular", "pitch": 0.3, "micro_f": None, "d": 1.5,
        "F": None, "A": None, "focus_mm": None, "D": None,
        # No main lens: every pinhole sees both spheres, each lens shows them d / z scaled about
        # its centre; 12 mm apart they land about 10 px apart in every microimage.
        "points_mm": [(6.0, 1.0, 200.0), (-6.0, -1.0, 150.0)],
        "blob_px": 1.5,
        "reach_px": 2.5,
    },
]


def main_distance(cfg):
    if cfg["D"] is not None:
        return cfg["D"]
    return pt.image_distance(cfg["F"], cfg["focus_mm"])  # 1/F = 1/z + 1/D


def depths(cfg):
    if cfg["depths_mm"] is not None:
        return cfg["depths_mm"]
    D, f, d, F = main_distance(cfg), cfg["micro_f"], cfg["d"], cfg["F"]
    a = f * d / (d - f)
    b = D - a
    return [b * F / (b - F)] * len(TARGETS)


def camera_block(cfg):
    if cfg["F"] is None:
        main = None
    else:
        main = "thin_lens focal_length %r aperture %r " % (cfg["F"], cfg["A"])
        if cfg["D"] is None:
            main += "focus_distance %r" % (cfg["focus_mm"] / MM_PER_UNIT)
        else:
            main += "distance %r" % cfg["D"]
    lens = "pinhole" if cfg["micro_f"] is None else "focal_length %r" % cfg["micro_f"]
    look_at = LOCATION + DIRECTION
    return """camera {
  plenoptic
  location <%r, %r, %r>
  look_at <%r, %r, %r>
  %s
  microlens_array { %s pitch %r %s distance %r }
  sensor { pixel_size %r }
  samples 36
}
""" % (tuple(LOCATION) + tuple(look_at) + ("" if main is None else "main_lens { %s }" % main,
                                            cfg["grid"], cfg["pitch"], lens, cfg["d"], PIXEL))


def sphere_points(cfg):
    """Sphere centres in the optics frame (mm) and radii (mm): each on the main-lens chief line
    towards its sensor target, sized to give a blob of about blob_px pixels."""
    if cfg["F"] is None:
        # Through a pinhole at distance z above the sensor plane d: blob = rho d / z.
        points = [np.array(p) for p in cfg["points_mm"]]
        return points, [cfg["blob_px"] * PIXEL * p[2] / cfg["d"] for p in points]
    D, d, F = main_distance(cfg), cfg["d"], cfg["F"]
    points, radii = [], []
    for (xs, ys), z in zip(TARGETS, depths(cfg)):
        # Chief line through the main-lens centre: the sensor point (xs, ys, -(D + d)) and the
        # object (-xs, -ys) z / (D + d) lie on one line through the origin.
        x, y = -xs * z / (D + d), -ys * z / (D + d)
        b = pt.image_distance(F, z)
        delta = abs(D - b)
        # The sphere's image (radius rho b / z, at delta from the array) reaches the sensor scaled
        # by d / delta: through a pinhole, along the chief lines of a d = f lens, or as the image
        # a focusing microlens makes (magnification d / a, a = delta).
        rho = cfg["blob_px"] * PIXEL * z * delta / (b * d)
        points.append(np.array([x, y, z]))
        radii.append(rho)
    return points, radii


def to_world(p_mm):
    return LOCATION + (p_mm[0] * RIGHT + p_mm[1] * UP + p_mm[2] * DIRECTION) / MM_PER_UNIT


def cone_crossing(image_point, through):
    """Where the line from the main-lens image point through an array point meets z = 0."""
    t = image_point[2] / (image_point[2] - through[2])
    return image_point[:2] + t * (through[:2] - image_point[:2])


def is_clean(cfg, point, rho, k, l, u, v):
    """(clean, own): clean when the image through lens (k, l) is wholly seen and so its centroid
    comparable: inside the picture, and the lens cell (or its pinhole, with a margin for the blob's
    rays) inside the cone from every part of the sphere's image to the main aperture; for a camera
    array, the blob clear of the cell border. own: the lens whose cell holds the predicted
    position, computed here (None when within half a pixel of a border)."""
    d, p = cfg["d"], cfg["pitch"]
    reach = cfg["reach_px"]
    if not (reach + 2 <= u <= W - 1 - reach - 2 and reach + 2 <= v <= H - 1 - reach - 2):
        return False, None
    xs = -(u - (W / 2.0 - 0.5)) * PIXEL
    ys = (v - (H / 2.0 - 0.5)) * PIXEL
    if cfg["F"] is None:
        # Camera array: a pixel belongs to the lens straight above it, and the cells tile the
        # sensor, so keep the blob off the cell border.
        kk, ll, gap = pt.nearest_lens_local(cfg["grid"], p, np.array([xs, ys]))
        border = gap / (2 * p * (math.sqrt(2) if cfg["grid"] == "rectangular" else 1.0))
        return border > (reach + 1.5) * PIXEL, (int(kk), int(ll))
    D, F, A = main_distance(cfg), cfg["F"], cfg["A"]
    b = pt.image_distance(F, point[2])
    image = np.array([-point[0] * b / point[2], -point[1] * b / point[2], -b])
    spread = rho * b / point[2]  # radius of the sphere's image
    centre = pt.lens_centre_local(cfg["grid"], p, k, l)
    if cfg["micro_f"] is None:
        corners = [centre]
        # Blob pixels' rays cross the main lens up to reach * pixel * D / d from the chief line.
        margin = reach * PIXEL * D / d
    else:
        half = p / 2.0
        if cfg["grid"] == "rectangular":
            offsets = [(-half, -half), (half, -half), (half, half), (-half, half)]
        else:
            r = p / math.sqrt(3)
            offsets = [(r * math.cos(math.radians(30 + 60 * i)), r * math.sin(math.radians(30 + 60 * i)))
                       for i in range(6)]
        corners = [centre + np.array(o) for o in offsets]
        margin = 0.05 * A
    for c in corners:
        for ex, ey in ((0, 0), (spread, 0), (-spread, 0), (0, spread), (0, -spread)):
            m = cone_crossing(image + np.array([ex, ey, 0]), np.array([c[0], c[1], -D]))
            if np.hypot(*m) > A / 2 - margin:
                return False, None
    # The lens whose cell holds the predicted position, seen from the main-lens centre on the
    # array plane (None within 0.5 px of a cell border, where either is right).
    kk, ll, gap = pt.nearest_lens_local(cfg["grid"], p, np.array([xs, ys]) * D / (D + d))
    # Distance to the cell border: (|q - c1|^2 - |q - c0|^2) / (2 |c1 - c0|), neighbours at most
    # p (hexagonal) or p sqrt(2) (rectangular, diagonal) apart.
    border = gap / (2 * p * (math.sqrt(2) if cfg["grid"] == "rectangular" else 1.0))
    own = (int(kk), int(ll)) if border > 0.5 * PIXEL * D / (D + d) else None
    # No need to keep the blob off the cell border as well: the whole f-number-matched disc of
    # light lies inside the cell in these set-ups (checked in run_config), and a lens inside the
    # cone puts the whole blob inside that disc.
    return True, own


def write_overlay(path, image, predicted, found, scale=3):
    """The render (brightened) with predictions (green: compared, yellow: not compared) and blob
    centroids (red), to look at when a check fails."""
    from PIL import Image, ImageDraw
    im = Image.fromarray((np.clip(image, 0, 1) ** 0.5 * 255).astype(np.uint8)).convert("RGB")
    im = im.resize((im.size[0] * scale, im.size[1] * scale), Image.NEAREST)
    draw = ImageDraw.Draw(im)
    for u, v, clean in predicted:
        x, y = (u + 0.5) * scale, (v + 0.5) * scale
        draw.ellipse([x - 6, y - 6, x + 6, y + 6], outline=(0, 255, 0) if clean else (255, 220, 0))
    for bl in found:
        x, y = (bl["u"] + 0.5) * scale, (bl["v"] + 0.5) * scale
        draw.point([(x, y)], fill=(255, 0, 0))
    im.save(path)


@pytest.mark.parametrize("cfg", CONFIGS, ids=[c["name"] for c in CONFIGS])
def test_projection(args, cfg):
    name = cfg["name"]
    points, radii = sphere_points(cfg)
    spheres = "\n".join("sphere { <%r, %r, %r>, %r pigment { rgb 1 } finish { emission 1 diffuse 0 ambient 0 } }"
                        % (tuple(to_world(p)) + (r / MM_PER_UNIT,)) for p, r in zip(points, radii))
    png, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "projection_" + name, camera_block(cfg) + spheres + "\n", W, H)
    meta = pt.read_json(meta_path)
    frame = meta["camera_frame"]
    frame_error = max(np.abs(np.array(frame["location"]) - LOCATION).max(),
                      np.abs(np.array(frame["right"]) - RIGHT).max(),
                      np.abs(np.array(frame["up"]) - UP).max(),
                      np.abs(np.array(frame["direction"]) - DIRECTION).max())
    assert (frame_error < 1e-9), ("%s: metadata camera_frame equals the scene's camera (largest difference %.2g)"
                 % (name, frame_error))

    # The light of each lens stays inside its own cell (so a blob is never cut by a cell border).
    lattice = meta["microimage_lattice"]
    if cfg["F"] is not None:
        spacing = min(math.hypot(*lattice["basis_px"][0]), math.hypot(*lattice["basis_px"][1]))
        disc = cfg["A"] * cfg["d"] / main_distance(cfg) / PIXEL
        assert (disc < spacing - 0.5), ("%s: the main aperture's disc behind each lens (%.2f px) fits its "
                     "cell (%.2f px)" % (name, disc, spacing))
    image = pt.read_linear(png).mean(axis=2)
    found = pt.blobs(image, 0.004)
    hits = pt.run_project(args.project, meta_path, [to_world(p) for p in points])
    assert (len(found) > 0 and len(hits) > 0), ("%s: %d blobs in the render, %d predicted images"
                 % (name, len(found), len(hits)))

    # plenoptic-project names lenses in row form; the metadata lattice counts skew indices:
    # k_skew = k - floor(l / 2) on a hexagonal grid (docs/ground-truth.md). Every image must lie
    # in its lens's microimage cell around that lattice centre.
    origin = np.array(lattice["origin_px"])
    basis_a, basis_b = np.array(lattice["basis_px"][0]), np.array(lattice["basis_px"][1])
    cell_px = 0.5 * min(np.hypot(*basis_a), np.hypot(*basis_b)) * (
        2 / math.sqrt(3) if cfg["grid"] == "hexagonal" else math.sqrt(2))  # circumradius
    far_from_lens = []
    for (index, k, l, u, v) in hits:
        k_skew = k - (l // 2) if cfg["grid"] == "hexagonal" else k
        centre = origin + k_skew * basis_a + l * basis_b
        if math.hypot(u - centre[0], v - centre[1]) > cell_px + 1e-6:
            far_from_lens.append((index, k, l, round(u, 2), round(v, 2), tuple(centre.round(2))))
    assert (not far_from_lens), ("%s: each image lies in the cell of its lens's lattice centre (row-form k -> "
                 "skew k - floor(l/2)); outside: %s" % (name, far_from_lens[:4]))

    overlay = []  # (u, v, clean) for the picture written beside the render
    errors, wrong_lens, missing = [], [], []
    explained = set()
    for (index, k, l, u, v) in hits:
        near = [i for i, bl in enumerate(found) if math.hypot(bl["u"] - u, bl["v"] - v) <= cfg["reach_px"] + 3]
        explained.update(near)
        clean, own = is_clean(cfg, points[index], radii[index], k, l, u, v)
        overlay.append((u, v, clean))
        if not clean:
            continue
        if own is not None and own != (k, l):
            wrong_lens.append((index, k, l, own))
        if not near:
            missing.append((index, k, l, u, v))
            continue
        best = min(near, key=lambda i: math.hypot(found[i]["u"] - u, found[i]["v"] - v))
        errors.append((math.hypot(found[best]["u"] - u, found[best]["v"] - v), index, k, l, u, v,
                       found[best]["u"], found[best]["v"]))
    assert (len(errors) >= 10), ("%s: %d predicted images are wholly seen and compared (need >= 10)"
                 % (name, len(errors)))
    assert (not missing), ("%s: every wholly seen predicted image shows a blob; missing: %s"
                 % (name, missing[:5]))
    assert (not wrong_lens), ("%s: each image's lens (k, l) is the lens whose cell holds it; "
                 "disagreements (point, k, l, expected): %s" % (name, wrong_lens[:5]))
    if errors:
        worst = max(errors)
        mean = sum(e[0] for e in errors) / len(errors)
        assert (worst[0] <= TOLERANCE_PX), ("%s: blob centroid - plenoptic-project <= %.2f px: mean %.3f px, worst %.3f px "
                     "(point %d lens (%d, %d): predicted (%.3f, %.3f), measured (%.3f, %.3f))"
                     % ((name, TOLERANCE_PX, mean) + worst))
    write_overlay(png[:-4] + "_check.png", image, overlay, found)
    # A blob no prediction explains is legitimate only when the sphere's centre line just misses
    # the aperture while part of the sphere still shows: then at most about half its light.
    fluxes = sorted(found[i]["flux"] for i in explained) or [0.0]
    median = fluxes[len(fluxes) // 2]
    unexplained = [bl for i, bl in enumerate(found) if i not in explained and bl["flux"] > 0.75 * median]
    assert (not unexplained), ("%s: every blob is an image plenoptic-project predicts; unexplained: %s"
                 % (name, [(round(b["u"], 2), round(b["v"], 2), round(b["flux"], 2)) for b in unexplained[:5]]))

