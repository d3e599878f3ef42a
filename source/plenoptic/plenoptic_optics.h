// SPDX-License-Identifier: AGPL-3.0-or-later
// The pure optics of the plenoptic camera: sensor points, ray generation, forward projection.

#ifndef PLENOPTIC_OPTICS_H
#define PLENOPTIC_OPTICS_H

#include <vector>

#include "plenoptic_lattice.h"
#include "plenoptic_model.h"
#include "plenoptic_sampling.h"

namespace plenoptic {

// A ray leaving the last optical element (the main-lens plane z = 0; the array when there is
// no main lens), in the optics frame, millimetres. The caller converts to scene units.
struct OpticsRay {
    double origin_mm[3];
    double dir[3];  // unit length, towards the scene (+z component)
};

// Point on the sensor (optics frame, mm) at continuous pixel coordinates (pu, pv), where pixel
// (i, j) spans [i, i+1) x [j, j+1); (i + 0.5, j + 0.5) is its centre:
//   x = -(pu - W/2) * sx + ox,  y = (pv - H/2) * sy + oy,  z = sensor plane.
Vec3 sensor_point(const Model& model, int W, int H, double pu, double pv);

// Inverse of sensor_point in the centre convention used by the metadata: pixel (i, j)'s centre is
// at (u, v) = (i, j). Returns whether the point lies inside the image.
bool sensor_to_pixel(const Model& model, int W, int H, double x_mm, double y_mm, double* u, double* v);

// Where the optical axis meets the sensor, centre convention.
Vec2 principal_point_px(const Model& model, int W, int H);

// Centre of a lens in the optics frame (posed array), mm.
Vec3 lens_centre_mm(const Model& model, LensIndex lens);

// The lens a sensor point belongs to: the lens whose cell contains the intersection of the line
// (main-lens centre -> point) with the array plane; with no main lens, the lens straight above
// the point. False when that line misses the array plane (only for extreme tilts).
bool own_lens(const Model& model, Vec3 sensor_point_mm, LensIndex* lens);

// The ray of one sample of pixel (i, j). `lens` forces the microlens the light passes through
// (overlap modelling); nullptr uses the own lens of the sample's sensor point. Returns false when
// an aperture blocks the ray (it then carries no light: black, opaque). No allocation, no
// search over lenses, no trigonometry except the concentric disc map of a bare main lens.
bool generate_ray(const Model& model, int W, int H, int i, int j, const CameraSample& sample,
                  const LensIndex* lens, OpticsRay* out);

// The lenses whose light can reach pixel (i, j) when the model models overlap: the pixel
// centre's own lens first, then every neighbour within model.overlap_rings rings that passes a
// conservative reach test (all of them for an array tilted by more than kMaxPrunedTiltSine).
// Without overlap modelling: the own lens only. Returns the count (0 if the pixel sees no lens),
// at most `capacity`.
int overlap_lenses(const Model& model, int W, int H, int i, int j, LensIndex* out, int capacity);

// The chief ray of pixel (i, j): pixel centre -> centre of its microlens (undeviated) -> refracted
// by the main lens; with no array, pixel centre through the main-lens centre; with a pinhole main
// lens, the pixel's only ray. Apertures are ignored (depth maps want a ray for every pixel).
// Falls back to the line from the pixel centre through the main-lens centre when the geometry
// has no such ray.
OpticsRay chief_ray(const Model& model, int W, int H, int i, int j);

// The same at continuous pixel coordinates (sensor_point's convention), optionally through a
// given lens. False when the geometry has no such ray.
bool chief_ray_through(const Model& model, int W, int H, double pu, double pv, const LensIndex* lens,
                       OpticsRay* out);

// One image of a 3-D point: lens (k, l) in row form ((0, 0) when there is no array) and the
// continuous pixel position, centre convention (pixel (i, j)'s centre at (i, j)).
struct PixelHit {
    LensIndex lens;
    double u, v;
};

// Every pixel position where a point (optics frame, mm) images, one per microlens that sees it.
// Thin main lens: the point's thin-lens image X' (homogeneous, so X' at infinity is fine); each
// lens whose cell meets the cone from the main aperture to X' images it along the line from X'
// through its centre (its chief ray). Kept only inside that lens's microimage cell and inside the
// image. Pinhole main lens: the single ray through the pinhole. No main lens: each lens images
// the point along the line through its centre (a camera array). No array: the chief ray through
// the main-lens centre. Points at or behind the main-lens plane image nowhere.
std::vector<PixelHit> forward_project(const Model& model, int W, int H, const double point_mm[3]);

// Centre of lens `lens`'s microimage in pixels (centre convention): the central projection of the
// posed lens centre from the main-lens centre onto the sensor (orthogonal without main lens).
bool microimage_centre_px(const Model& model, int W, int H, LensIndex lens, double* u, double* v);

// The microimage-centre lattice in pixel coordinates (centre convention) and its LFToolbox form.
// centre(k_s, l) = origin + k_s a + l b in skew indices (a = (p, 0); b = (p/2, p sqrt(3)/2)
// hexagonal, (0, p) rectangular). Exact (up to rounding) for arrays not tilted about x or y;
// otherwise a and b are the affine map at the array centre (exact = false) while the origin is
// still exact.
struct MicroimageLattice {
    bool valid;              // false without array
    double origin_px[2];
    double basis_a_px[2];
    double basis_b_px[2];
    bool exact;
    // LFToolbox LensletGridModel, 1-based MATLAB pixels (first pixel's centre at (1, 1)).
    // Its grid: uu = col * HSpacing (+ HSpacing/2 on 1-based rows FirstPosShiftRow:2:end),
    // vv = row * VSpacing, rotated by [cos -sin; sin cos](Rot), plus (HOffset, VOffset).
    // Normalised as LFToolbox's LFBuildLensletGridModel normalises its estimate: the origin's
    // projections on the rotated axes lie in [0, HSpacing/2) and [0, VSpacing), so (row 1, col 1)
    // is the top-left lenslet of the first row (first_lens) and the origin is that lenslet
    // (FirstPosShiftRow 2) or half a spacing left of it (FirstPosShiftRow 1); UMax and VMax as
    // LFToolbox computes them. Exact for square pixels and no tilt about x or y; otherwise derived
    // from the basis vectors above.
    bool lftoolbox_valid;
    double h_spacing, v_spacing, h_offset, v_offset, rot;
    int first_pos_shift_row; // 1 or 2 for hexagonal grids; 0 for rectangular (LFToolbox cannot express it)
    long long u_max, v_max;
    LensIndex first_lens;    // the lenslet at LFToolbox's (row 1, col 1), row form
};

MicroimageLattice microimage_lattice(const Model& model, int W, int H);

} // namespace plenoptic

#endif
