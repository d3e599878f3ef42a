// SPDX-License-Identifier: AGPL-3.0-or-later
// Samples where light passes: behind an array, the main lens lights only part of each microlens
// cell (and a pixel at a microimage's rim only part of its area). For ideal thin microlenses
// (Microlens::aims) behind an image-forming main lens and an array parallel to the sensor, the
// camera aims a pixel's samples at a conservative region holding every point where light can pass
// and weights each sample by the sampled area over the whole (OpticsRay::weight), so that a pixel's
// value is an unbiased estimate of the one uniform samples give.
//
// The geometry (array-local frame, lens centre c, focal length f, sensor point s at distance d
// behind the lens plane): the ray from s through cell point h leaves the thin lens with slope
// (h - s) / d - (h - c) / f, so it crosses the plane at distance Z in front of the lens at
//     x(h, s) = g h - (Z / d) s + (Z / f) c,   g = 1 + Z / d - Z / f,
// affine in h and in s. Light passes the main lens only where x lies in a disc (centre m, radius
// rho) of that plane: the thin lens's aperture, the thick lens's exit pupil (both exact), a traced
// lens's pupil bounds (PupilBounds::discs_holding over the cell, a disc and up to four cutting discs:
// conservative). So
//  - for a sensor point, the cell points whose rays can pass lie in the disc of centre
//    (m + (Z / d) s - (Z / f) c) / g and radius rho / |g| (lit_cell_disc), intersected with the
//    cell (lit_cell_x_range: the exact x range of that part);
//  - some cell point's ray from s can pass exactly when that disc meets the cell H (a polygon about
//    c), i.e. when s lies in c + (c - m) d / Z + (|g| d / Z) H widened by rho d / Z
//    (lit_sensor_region: the microimage, exactly for one disc; behind a traced lens the
//    intersection of the regions of its discs, which holds the exact one);
//  - the renderer takes a sensor point's light through its own lens (own_lens: the lens whose cell
//    holds the point's projection from the exit pupil's centre), so through that lens only from the
//    cell's projection onto the sensor (own_sensor_cell; with errors, the displaced centres' cell).
// Each region is sampled by its chords: x uniform over the region's exact x range, then y uniform
// over the chord at x; the weight is the x range times the chord over the whole's area.
// A lens tilted by its errors is a thin lens in its own frame (turned about its centre), so all of
// the above holds there (lens_aim): the main lens's discs, tilted by t in that frame, are replaced
// by discs of its plane Z holding where the passing rays cross it (rho widened by rho sin t times
// the steepest passing ray's slope); the sensor's plane is tilted there too, so a pixel's region is
// taken at its centre's distance and widened by how far it moves over the pixel (sensor_region).

#ifndef PLENOPTIC_AIM_H
#define PLENOPTIC_AIM_H

#include <cmath>

#include "plenoptic/array/microlens.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/core/lattice.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

// A disc in a plane parallel to the array (array-local x, y). Radius infinite: the whole plane.
struct AimDisc {
    Vec2 centre;
    double radius;
};

// What aiming needs of one lens (array-local, mm): its centre and plane, focal length, the cell
// (grid, pitch, circumradius), and the disc of the plane Z in front of it (Z > 0) where light can pass the main
// lens (radius 0: none passes through this lens).
struct LensAim {
    LensIndex lens;
    Vec2 c;
    double z;
    double f;
    GridType grid;
    double pitch;
    double circumradius;
    double Z;
    Vec2 m;
    double rho;
    // Behind a traced lens, off the axis: `cuts` (0, 2 or 4) more discs of that plane, each also
    // holding where light can pass (PupilBounds::discs_holding); light passes only in all of them.
    static const int kMaxCuts = PupilBounds::kMaxDiscs - 1;
    int cuts;
    Vec2 cut_m[kMaxCuts];
    double cut_rho[kMaxCuts];
    // A lens tilted by its errors: everything above but c and z is in its own frame (the
    // array-local one turned about its centre to its axis: a point q is c3 + axes^T (q - c3) there,
    // c3 = (c, z)), and the cell is the lattice's cell in that frame (Microlens::cell_ray's
    // offsets). m, Z, rho and the cuts are discs of the lens frame's plane Z in front that hold the
    // main lens's discs, which are tilted there (lens_aim). sin_tilt: the sine of the tilt.
    bool tilted = false;
    Mat3 axes = identity_mat3();
    double sin_tilt = 0;
    // For a tilted lens's cell points (tilted_cell_discs), the main lens's discs as they are: their
    // centres in the lens's frame (from its centre; the main disc first, then the cuts'), their
    // radii, and their plane's normal there.
    Vec3 disc_centre[1 + kMaxCuts];
    double disc_radius[1 + kMaxCuts];
    Vec3 disc_normal;
    // For a tilted lens's pixel regions, each flattened disc more tightly (the main disc's first,
    // then the cuts'): the shadow, an ellipse, with its parallax lies within seg_rho[k] of the
    // segment from its centre - seg[k] to its centre + seg[k] (seg[k] along the ellipse's major
    // axis, as long as its semi-axes' difference). seg[k] zero: the disc (m, rho) alone.
    Vec2 seg[1 + kMaxCuts] = {};
    double seg_rho[1 + kMaxCuts] = {};

    // Disc `cut`'s (-1: the main disc) stadium for the pixel regions: whether it has one, its
    // half-segment and its radius (else the flattened disc's radius).
    bool has_stadium(int cut) const { return seg[cut + 1].x != 0 || seg[cut + 1].y != 0; }
    double disc_rho(int cut) const { return cut < 0 ? rho : cut_rho[cut]; }
    double pixel_rho(int cut) const { return has_stadium(cut) ? seg_rho[cut + 1] : disc_rho(cut); }
};

// A point (array-local) in the lens's own frame (itself for an untilted lens).
Vec3 lens_frame_point(const LensAim& aim, Vec3 q);

// Whether the camera aims its samples (PlenopticCamera::sampling.aim): behind an image-forming main
// lens, with an array parallel to the sensor whose microlenses aim (Microlens::aims; lenses tilted
// by their errors too), no clear gap, and more than one sample per pixel (one sample is the chief
// ray). make_camera sets it; the camera can clear it.
bool camera_can_aim(const PlenopticCamera& model);

// The lens's aim data; false when the lens cannot be aimed at (then sample it uniformly): a traced
// main lens without pupil bounds, a limiting plane not in front of it. Behind a traced lens the
// bounds are for points of one plane: a lens off it (displaced along the axis, or tilted, whose
// cell leaves the plane) has its cell's rays' lines cross that plane within (how far off) times
// (the steepest passing ray's slope, from PupilBounds::reach_mm) of their points, so its discs
// hold those of a cell widened by that much.
bool lens_aim(const PlenopticCamera& model, LensIndex lens, LensAim* out);

// A convex region of a plane: the points within `radius` of a convex polygon (`corners` corners in
// order, either way round; one corner: a disc).
struct RoundedPolygon {
    int corners;
    Vec2 corner[8];  // a cell's six, and two more where a segment widens it (lit_sensor_region)
    double radius;
};
// Whether p lies in the region.
bool region_holds(const RoundedPolygon& r, Vec2 p);
// The region's x range.
void region_x_extent(const RoundedPolygon& r, double* x0, double* x1);
// The region's chord at x, [*y0, *y1]; false when x lies outside its x range.
bool region_chord(const RoundedPolygon& r, double x, double* y0, double* y1);
// The region's convex polygon widened by the segment from -u to u (its radius unchanged); false,
// r unchanged, when the result would not fit a RoundedPolygon.
bool widen_by_segment(RoundedPolygon* r, Vec2 u);

// The region of sensor points (x, y of the lens's frame; the sensor d behind the lens plane, d > 0)
// from which a ray through the lens's cell can pass the main lens's disc (k = -1) or cutting disc
// k (0 to cuts - 1): the cell polygon scaled by |g| d / Z about c + (c - m) d / Z, widened by
// rho d / Z.
RoundedPolygon lit_sensor_region(const LensAim& aim, double d, int k = -1);

// The same in the array's frame for the points of the plane through s parallel to the array
// within `reach` of s (array-local): lit_sensor_region at s's distance for an untilted lens (reach
// unused); for a tilted one, where that plane is tilted in the lens's frame, widened by how far
// the region moves over the reach's range of distances and mapped back to that plane (the map's
// inverse widens a radius by at most 1 / cos(tilt)).
RoundedPolygon sensor_region(const LensAim& aim, Vec3 s, double reach, int k = -1);

// A half-plane {p : dot(normal, p) <= offset}.
struct HalfPlane {
    Vec2 normal;
    double offset;
};

// The sensor points (array-local x, y, in the sensor's plane at array-local z sensor_z) whose own
// lens (rays.h: own_lens) can be `lens`: its cell projected from the exit pupil's centre onto the
// sensor, as the half-planes (up to 8) of the points nearer its centre than each neighbour's (the
// lattice's, or the displaced centres of an array with errors: nearest_displaced finds the nearest
// displaced centre, whose cell its neighbours' bisectors bound); how many. 0 when the projection
// is not defined (then any point may be).
int own_sensor_cell(const PlenopticCamera& model, LensIndex lens, double sensor_z, HalfPlane out[8]);

// The disc of cell points (array-local, from the lens's centre) holding every point through which
// the ray from sensor point s (array-local, behind the lens) can pass the main lens; infinite
// radius when every point can (g = 0). For a tilted lens (cell points in its own frame), the cell
// points whose rays meet a disc of the main lens's plane form an ellipse: every ray from s leaves
// the thin lens through s's image I, so they are the points of the lens's plane that the cone from
// I over the disc cuts, a tilted section. Its disc is the disc of radius the ellipse's largest
// radius of curvature tangent to it inside where the line from its centre to the cell's centre
// meets it, which holds the whole ellipse (Blaschke's rolling theorem) and leaves near the cell
// only what the curvatures' difference leaves (nanometres for micrometre cells).
AimDisc lit_cell_disc(const LensAim& aim, Vec3 s);
// The same for cutting disc k (0 to cuts - 1) of the lens's plane instead of its disc.
AimDisc lit_cell_cut(const LensAim& aim, Vec3 s, int k);

// The x range (from the lens's centre) of the cell's part where light from sensor point s can pass
// (the cell within lit_cell_disc and the cuts' discs), exactly up to rounding (widened by it); false when
// that part is empty.
bool lit_cell_x_range(const LensAim& aim, Vec3 s, double* x0, double* x1);

// Half the height of a lens's cell (core/lattice.h: cell_polygon, centred on the lens) at x from its
// centre; negative outside the cell's x range.
double cell_half_height(GridType grid, double pitch_mm, double x);

// Where a sample of pixel (i, j) looks (the pixel point (pu, pv) in pixel coordinates, corner
// convention) and through which lens, with the weight of that choice. When the pixel lies partly
// outside the region where light through its centre's lens lands (lit_sensor_region and the cuts',
// within own_sensor_cell), the point is drawn from the pixel's part in the union of the regions of
// that lens and its neighbours (the lenses whose own regions the pixel can meet; with a forced lens,
// overlap modelling, that lens's region alone, and then lens_forced); a pixel that no light reaches
// gets no point (passed false). Otherwise the sample's own point, weight 1.
struct PixelAim {
    double pu, pv;
    double weight;
    bool lens_forced;
    LensIndex lens;
    bool passed;
};
PixelAim aim_pixel(const PlenopticCamera& model, int i, int j, double pixel_u, double pixel_v, const LensIndex* forced);

// False when no light through `lens` can reach pixel (i, j): the pixel meets none of the lens's
// conservative region where its light lands (aim_pixel through that lens would give no point).
// True when it may. The plan is kept for the pixel's samples (the same cache as aim_pixel's).
bool aim_reaches_pixel(const PlenopticCamera& model, int i, int j, LensIndex lens);

// The ray from sensor point p through `lens` for aperture sample (u, v), drawn from the part of
// the cell where light from p can pass (lit_cell_disc and the cuts', over lit_cell_x_range), with
// *weight that part's sampled measure over the cell's area; the uniform sample_ray (weight 1) when that part holds the whole cell or
// the lens cannot be aimed at. Not passed when no point of the cell can pass.
ArrayRay aimed_cell_ray(const PlenopticCamera& model, const Vec3& p, LensIndex lens, double u, double v, double* weight);

} // namespace plenoptic

#endif
