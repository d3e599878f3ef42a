# SPDX-License-Identifier: AGPL-3.0-or-later
"""The metadata's microimage lattice against the microimages a white scene shows.

Inside a white sky every microimage is the bright disc of the main aperture seen through its
lens. The brightness centroid of each disc (measured in a window re-centred on the measurement)
is its centre. For a hexagonal array, a rotated and shifted rectangular array, and a rotated
hexagonal array behind a shifted sensor, the test checks that

  - the metadata's lattice (origin + k a + l b) is on the measured centres, 0.1 px on average;
  - the LFToolbox LensletGridModel in the metadata, built into a grid the way LFToolbox's
    LFBuildHexGrid does it (1-based pixels), lands on the same centres;
  - the metadata's numbers equal the formulas of docs/specification.md evaluated here: the principal point,
    the lattice origin and basis (lens centres projected from the main-lens centre), and the
    diameter of the aperture's disc (A d / D, also measured from the disc's area).
"""

import math

import numpy as np

import pytest

import plenoptic_testing as pt

W, H = 320, 240
PIXEL = 0.01
F, N, FOCUS = 50.0, 5.6, 1.5  # main lens: the f-number leaves dark gaps between the discs

CASES = [
    {"name": "hexagonal", "grid": "hexagonal", "pitch": 0.15, "f": 0.45, "d": 0.45,
     "rotate": 0.0, "translate": (0.0, 0.0), "offset": (0.0, 0.0)},
    {"name": "rectangular-rotated", "grid": "rectangular", "pitch": 0.14, "f": 0.5, "d": 0.55,
     "rotate": 3.0, "translate": (0.013, -0.007), "offset": (0.0, 0.0)},
    {"name": "hexagonal-rotated-offset", "grid": "hexagonal", "pitch": 0.16, "f": 0.5, "d": 0.5,
     "rotate": -2.0, "translate": (-0.004, 0.011), "offset": (0.031, -0.017)},
]


def scene(case):
    return """camera {
  plenoptic
  location <0, 0, 0>
  look_at <0, 0, 1>
  main_lens { thin_lens focal_length %r f_number %r focus_distance %r }
  microlens_array { %s pitch %r focal_length %r distance %r rotate <0, 0, %r> translate <%r, %r, 0> }
  sensor { pixel_size %r offset <%r, %r> }
  samples 16
}
sky_sphere { pigment { rgb 1 } }
""" % (F, N, FOCUS, case["grid"], case["pitch"], case["f"], case["d"], case["rotate"],
       case["translate"][0], case["translate"][1], PIXEL, case["offset"][0], case["offset"][1])


def measure_centre(image, u, v, radius, iterations=6):
    """Brightness centroid in a disc window of `radius` around (u, v), re-centred each time."""
    H_, W_ = image.shape
    for _ in range(iterations):
        i0, i1 = max(int(math.floor(u - radius)), 0), min(int(math.ceil(u + radius)), W_ - 1)
        j0, j1 = max(int(math.floor(v - radius)), 0), min(int(math.ceil(v + radius)), H_ - 1)
        jj, ii = np.mgrid[j0:j1 + 1, i0:i1 + 1]
        inside = (ii - u) ** 2 + (jj - v) ** 2 <= radius * radius
        w = image[j0:j1 + 1, i0:i1 + 1] * inside
        total = w.sum()
        if total <= 0:
            return None, 0.0
        u, v = (w * ii).sum() / total, (w * jj).sum() / total
    return (u, v), total


def lftoolbox_grid(model):
    """Grid of lenslet centres as LFToolbox's LFBuildHexGrid builds it (1-based pixels):
    uu = (col-1) HSpacing (+ HSpacing/2 on rows FirstPosShiftRow:2:end), vv = (row-1) VSpacing,
    rotated by [cos -sin; sin cos](Rot), plus (HOffset, VOffset). A rectangular grid has no
    shifted rows (FirstPosShiftRow null)."""
    rows, cols = np.mgrid[0:model["VMax"], 0:model["UMax"]]
    uu = cols * model["HSpacing"]
    vv = rows * model["VSpacing"]
    shift = model["FirstPosShiftRow"]
    if shift is not None:
        uu = uu + np.where((rows + 1 >= shift) & ((rows + 1 - shift) % 2 == 0), 0.5 * model["HSpacing"], 0.0)
    c, s = math.cos(model["Rot"]), math.sin(model["Rot"])
    return c * uu - s * vv + model["HOffset"], s * uu + c * vv + model["VOffset"]


def expected_metadata(case):
    """Principal point, lattice origin and basis, disc diameter from docs/specification.md (sections 2, 3)."""
    D = pt.image_distance(F, FOCUS * 1000.0)
    d, p = case["d"], case["pitch"]
    ox, oy = case["offset"]
    principal = pt.sensor_to_pixel(0.0, 0.0, W, H, PIXEL, PIXEL, ox, oy)
    scale = (D + d) / D  # central projection from the main-lens centre, array -> sensor
    R = pt.rot_z(case["rotate"])
    t = np.array(case["translate"])

    def px(local):
        x, y = (t + R @ np.asarray(local)) * scale
        return np.array(pt.sensor_to_pixel(x, y, W, H, PIXEL, PIXEL, ox, oy))

    origin = px([0.0, 0.0])
    b_local = [p / 2, p * math.sqrt(3) / 2] if case["grid"] == "hexagonal" else [0.0, p]
    a = px([p, 0.0]) - origin
    b = px(b_local) - origin
    aperture = F / N
    return np.array(principal), origin, a, b, aperture * d / D / PIXEL


@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in CASES])
def test_lattice(args, case):
    name = case["name"]
    png, meta_path, _ = pt.render_ground_truth(args.povray, args.work, "lattice_" + name, scene(case), W, H)
    meta = pt.read_json(meta_path)
    lattice = meta["microimage_lattice"]
    image = pt.read_linear(png).mean(axis=2)

    principal, origin, a, b, diameter = expected_metadata(case)
    m_origin = np.array(lattice["origin_px"])
    m_a, m_b = np.array(lattice["basis_px"][0]), np.array(lattice["basis_px"][1])
    assert np.abs(np.array(meta["principal_point_px"]) - principal).max() < 1e-6, "%s: principal_point_px %s = specification %s" % (name, meta["principal_point_px"], principal.tolist())
    largest = max(np.abs(m_origin - origin).max(), np.abs(m_a - a).max(), np.abs(m_b - b).max())
    assert (largest < 1e-6), ("%s: lattice origin %s a %s b %s = specification origin %s a %s b %s"
                 % (name, m_origin.round(6).tolist(), m_a.round(6).tolist(), m_b.round(6).tolist(),
                    origin.round(6).tolist(), a.round(6).tolist(), b.round(6).tolist()))
    assert (abs(lattice["microimage_diameter_px"] - diameter) < 1e-6), ("%s: microimage_diameter_px %.6f = A d / D / pixel %.6f"
                 % (name, lattice["microimage_diameter_px"], diameter))
    assert lattice["exact"] is True, "%s: lattice marked exact (the array is not tilted)" % name

    # Measure every microimage whose window lies inside the picture.
    spacing = min(np.hypot(*m_a), np.hypot(*m_b))
    window = 0.5 * spacing
    inv = np.linalg.inv(np.column_stack([m_a, m_b]))
    corners = np.array([[0, 0], [W - 1, 0], [0, H - 1], [W - 1, H - 1]], float) - m_origin
    kl = corners @ inv.T
    predicted, measured, areas = [], [], []
    for k in range(int(kl[:, 0].min()) - 2, int(kl[:, 0].max()) + 3):
        for l in range(int(kl[:, 1].min()) - 2, int(kl[:, 1].max()) + 3):
            u, v = m_origin + k * m_a + l * m_b
            if not (window + 1 <= u <= W - 2 - window and window + 1 <= v <= H - 2 - window):
                continue
            centre, total = measure_centre(image, u, v, window)
            if centre is None:
                continue
            predicted.append((u, v))
            measured.append(centre)
            areas.append(total)
    predicted, measured = np.array(predicted), np.array(measured)
    assert len(measured) >= 100, "%s: %d microimages measured (need >= 100)" % (name, len(measured))
    error = np.hypot(*(measured - predicted).T)
    assert (error.mean() <= 0.1 and error.max() <= 0.3), ("%s: metadata lattice - measured centres: mean %.4f px (<= 0.1), worst %.4f px (<= 0.3)"
                 % (name, error.mean(), error.max()))

    # The disc's area (white = 1) gives its diameter.
    measured_diameter = 2 * math.sqrt(np.median(areas) / math.pi)
    assert (abs(measured_diameter - diameter) <= 0.02 * diameter), ("%s: disc diameter from its area %.3f px = A d / D / pixel %.3f px (2%%)"
                 % (name, measured_diameter, diameter))

    # LFToolbox's grid, 1-based, against the measured centres. As in LFToolbox, the grid is a
    # (rotated) block of UMax x VMax points from (HOffset, VOffset): with a rotated lattice some
    # of its points fall outside the image and a few microimages near the corners outside it.
    model = meta["lftoolbox_lenslet_grid_model"]
    gu, gv = lftoolbox_grid(model)
    grid = np.column_stack([gu.ravel() - 1, gv.ravel() - 1])
    distance = np.array([np.hypot(*(grid - m).T).min() for m in measured])
    covered = distance <= 0.3
    assert (covered.mean() >= 0.9), ("%s: LFToolbox's %d x %d grid covers %.1f%% of the measured microimages"
                 % (name, model["UMax"], model["VMax"], 100 * covered.mean()))
    interior = ((grid[:, 0] >= window + 1) & (grid[:, 0] <= W - 2 - window)
                & (grid[:, 1] >= window + 1) & (grid[:, 1] <= H - 2 - window))
    error = np.array([np.hypot(*(measured - g).T).min() for g in grid[interior]])
    assert (len(error) > 0 and error.mean() <= 0.1 and error.max() <= 0.3), ("%s: LFToolbox grid points inside the image - measured centres: mean %.4f px, worst %.4f px "
                 "(%d points)" % (name, error.mean(), error.max(), len(error)))

