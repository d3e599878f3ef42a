// SPDX-License-Identifier: AGPL-3.0-or-later
// Microimage ground truth: each lens's white-scene microimage, integrated through the renderer's
// own rays (see the header).

#include "plenoptic/truth/microimages.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <unordered_map>

#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/array/refracting_microlens.h"
#include "plenoptic/lens/pupil_bounds.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/camera/rays_internal.h"
#include "plenoptic/core/sampling.h"

namespace plenoptic {

namespace {

using detail::project_to_array;

const int kCoarseSearch = 24;   // grid points a side when the start point is dark
const int kMaxDoublings = 8;    // of the bracket, when a boundary lies beyond it
const int kMaxBisections = 60;

// Area and first moments of light over the sensor, in pixels (corner convention: pixel (i, j)
// spans [i, i + 1) x [j, j + 1)).
struct Moments {
    double area, mu, mv;
};

// Whether sensor point (u, v) (corner-convention pixels) receives light through the lens at
// aperture sample (lens_u, lens_v), as the renderer decides it.
class LensProbe {
public:
    LensProbe(const PlenopticCamera& m, LensIndex lens, double lens_u, double lens_v)
        : m_(m), lens_(lens), lens_u_(lens_u), lens_v_(lens_v)
    {
    }

    bool lit(double u, double v) const
    {
        const CameraSample sample{u, v, lens_u_, lens_v_};
        const OpticsRay ray = generate_ray_unaimed(m_, 0, 0, sample, &lens_);
        if (!ray.passed)
            return false;
        if (m_.overlap.modelled)
            return true;
        // Without overlap modelling the renderer gives a sensor point the light of its own lens only.
        const OwnLens own = own_lens(m_, m_.sensor.point(u, v));
        return own.found && own.lens == lens_;
    }

    // Whether the light sensor point (u, v) receives through the lens at that aperture sample
    // passes the array after crossing into a neighbour's column (refracting lenses without baffles).
    bool crosses_cells(double u, double v) const
    {
        return refracting_sample_crosses_cells(m_.array, m_.sensor.point(u, v), lens_, lens_u_, lens_v_);
    }

private:
    const PlenopticCamera& m_;
    LensIndex lens_;
    double lens_u_, lens_v_;
};

// A start point inside the lit region: `guess` if lit, else the centroid of the lit points of a
// coarse grid over the square of half side `reach` around it (or the lit grid point nearest that
// centroid). False when the grid finds no light.
bool start_point(const LensProbe& probe, double gu, double gv, double reach, double* su, double* sv)
{
    if (probe.lit(gu, gv)) {
        *su = gu;
        *sv = gv;
        return true;
    }
    std::vector<Vec2> lit;
    const double step = 2 * reach / kCoarseSearch;
    for (int j = 0; j < kCoarseSearch; ++j)
        for (int i = 0; i < kCoarseSearch; ++i) {
            const double u = gu - reach + (i + 0.5) * step, v = gv - reach + (j + 0.5) * step;
            if (probe.lit(u, v))
                lit.push_back(Vec2{u, v});
        }
    if (lit.empty())
        return false;
    Vec2 mean{0, 0};
    for (const Vec2& p : lit)
        mean = mean + (1.0 / lit.size()) * p;
    if (probe.lit(mean.x, mean.y)) {
        *su = mean.x;
        *sv = mean.y;
        return true;
    }
    const Vec2* nearest = &lit[0];
    for (const Vec2& p : lit)
        if (length(p - mean) < length(*nearest - mean))
            nearest = &p;
    *su = nearest->x;
    *sv = nearest->y;
    return true;
}

// A bracket [lo lit, hi dark] of the boundary radius along direction (c, s) from the start point
// (su, sv), from scratch: near the previous direction's radius when that holds, grown by doubling
// while its outer end is lit (at most kMaxDoublings times).
void bracket_from_scratch(const LensProbe& probe, double su, double sv, double c, double s, double previous,
                          double reach, double* lo, double* hi)
{
    *lo = 0;
    *hi = reach;
    if (previous > 0) {
        const double inner = 0.8 * previous, outer = 1.25 * previous + 0.5;
        if (probe.lit(su + inner * c, sv + inner * s))
            *lo = inner;
        if (outer < *hi && !probe.lit(su + outer * c, sv + outer * s))
            *hi = outer;
    }
    for (int k = 0; k < kMaxDoublings && probe.lit(su + *hi * c, sv + *hi * s); ++k) {
        *lo = *hi;
        *hi *= 2;
    }
}

// The boundary radius along (c, s) from scratch: that bracket bisected until it is tolerance_px
// narrow; its middle.
double boundary_from_scratch(const LensProbe& probe, double su, double sv, double c, double s, double previous,
                             double reach, double tolerance_px)
{
    double lo, hi;
    bracket_from_scratch(probe, su, sv, c, s, previous, reach, &lo, &hi);
    for (int k = 0; k < kMaxBisections && hi - lo > tolerance_px; ++k) {
        const double mid = 0.5 * (lo + hi);
        if (probe.lit(su + mid * c, sv + mid * s))
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

// The boundary radius along (c, s) on the grid of radii j tolerance_px (j = 0, 1, ...): the middle of
// the grid step [j, j + 1] whose inner end is lit and outer end dark, sought near a predicted radius
// when there is one (from the previous lenses of the row: the step there and the next one checked,
// then walked inwards or outwards in doubling steps, the first first_step grid steps long, until a
// lit and a dark end hold the boundary),
// else from the bracket a search from scratch finds, then bisected down to one step. The points
// between the start point and the boundary are taken lit and those beyond it dark (the region is
// star-shaped about the start point), so the answer, within half a step of a crossing as the middle
// of a bisected bracket is, does not depend on the prediction: the lenses' results depend on the
// lenses alone, not on the order they are measured in.
double boundary_on_grid(const LensProbe& probe, double su, double sv, double c, double s, bool has_prediction,
                        double predicted, long long first_step, double previous, double reach, double tolerance_px,
                        bool* as_predicted)
{
    *as_predicted = false;
    const double farthest = reach * (1 << kMaxDoublings);
    const long long last = (long long)(farthest / tolerance_px) + 1;
    auto lit = [&](long long j) {
        if (j <= 0)
            return true;  // the start point
        const double r = j * tolerance_px;
        return probe.lit(su + r * c, sv + r * s);
    };
    long long lo = 0, hi = last;  // lit, dark
    bool bracketed = false;
    if (has_prediction && predicted > 0 && predicted < farthest) {
        const long long j = (long long)std::floor(predicted / tolerance_px);
        const bool inner = lit(j), outer = lit(j + 1);
        if (inner && !outer) {
            *as_predicted = true;
            return (j + 0.5) * tolerance_px;
        }
        if (!inner && !outer) {
            // The boundary lies inside: walk in until lit (the start point itself is lit).
            long long step = first_step;
            hi = j;
            for (;;) {
                lo = hi - step;
                if (lo <= 0 || lit(lo))
                    break;
                hi = lo;
                step *= 2;
            }
            lo = std::max(lo, 0LL);
            bracketed = true;
        } else if (inner && outer) {
            // Outside: walk out until dark, no farther than a search from scratch would go.
            long long step = first_step;
            lo = j + 1;
            for (;;) {
                hi = lo + step;
                if (hi >= last || !lit(hi))
                    break;
                lo = hi;
                step *= 2;
            }
            hi = std::min(hi, last);
            bracketed = true;
        }
        // (A lit outer end beyond a dark inner one: not star-shaped there; search from scratch.)
    }
    if (!bracketed) {
        // The bracket a search from scratch finds, widened to grid steps.
        double rlo, rhi;
        bracket_from_scratch(probe, su, sv, c, s, previous, reach, &rlo, &rhi);
        lo = (long long)std::floor(rlo / tolerance_px);
        hi = std::max(lo + 1, (long long)std::ceil(rhi / tolerance_px));
    }
    while (hi - lo > 1) {
        const long long mid = lo + (hi - lo) / 2;
        if (lit(mid))
            lo = mid;
        else
            hi = mid;
    }
    return (lo + 0.5) * tolerance_px;
}

// How a region's radii differ from their prediction (the previous lenses'): a + b cos(theta) +
// c sin(theta), a change of size and a move of the region, such as a displaced, tilted or rescaled
// lens gives all of its regions alike.
struct RadiusChange {
    double a = 0, b = 0, c = 0;
    double at(double cosine, double sine) const { return a + b * cosine + c * sine; }
};

// The lit region star-shaped about a start point: boundary radius per direction, then area and
// moments in polar form (trapezoid rule over the periodic angle). With `predicted` (the radii of
// the same region of the previous lenses of the row, per direction, as seen from `reference`) each
// radius is sought near its prediction, corrected by `change` (in: the lens's previous region's;
// out: this region's, fitted as the directions are measured); `radii` (if given) receives this
// region's radii as seen from `reference` (empty when there is no region). `lobe` (if given) is
// set when the region is a lobe of light that crossed into a neighbour's column in the array,
// found apart from the light that stays in the lens's own column: its start point came from the
// coarse search (the guess was dark) and receives such light.
Moments region_moments(const LensProbe& probe, double gu, double gv, double search, double reach,
                       const MicroimageOptions& options, Vec2 reference, const std::vector<double>* predicted,
                       RadiusChange* change, std::vector<double>* radii, bool* lobe = nullptr)
{
    if (radii)
        radii->clear();
    double su, sv;
    if (!start_point(probe, gu, gv, search, &su, &sv))
        return Moments{0, 0, 0};
    if (lobe)
        *lobe = !(su == gu && sv == gv) && probe.crosses_cells(su, sv);
    const bool near = predicted && int(predicted->size()) == options.azimuths && change;
    const RadiusChange start = change ? *change : RadiusChange();
    RadiusChange now = start;
    // Least squares of the differences from `start` over (1, cos, sin), drawn towards no difference
    // in its move (a ridge of weight 2: a few neighbouring directions cannot tell a move from a resize).
    double n11 = 1e-3, n12 = 0, n13 = 0, n22 = 2, n23 = 0, n33 = 2, r1 = 0, r2 = 0, r3 = 0;
    const double dtheta = 2 * kPi / options.azimuths;
    const double significant = 2 * options.tolerance_px;  // below it a change is the radii's own noise
    double area = 0, mu = 0, mv = 0, previous = 0;
    long long first_step = 1;  // of a walk from a failed prediction: about the last miss
    for (int a = 0; a < options.azimuths; ++a) {
        const double c = std::cos(a * dtheta), s = std::sin(a * dtheta);
        double r;
        bool as_predicted = false;
        // (Radii are exchanged as seen from `reference`, to first order in the start point's offset
        // from it: the start point moves from lens to lens, the boundary smoothly.)
        const double from_start = (su - reference.x) * c + (sv - reference.y) * s;
        const bool corrected =
            std::max(std::fabs(now.a), std::max(std::fabs(now.b), std::fabs(now.c))) > significant;
        const double guess = near ? (*predicted)[a] - from_start + (corrected ? now.at(c, s) : 0) : 0;
        if (options.reuse_neighbours)
            r = boundary_on_grid(probe, su, sv, c, s, near, guess, first_step, previous, reach,
                                 options.tolerance_px, &as_predicted);
        else
            r = boundary_from_scratch(probe, su, sv, c, s, previous, reach, options.tolerance_px);
        // What the next lens is predicted from: the prediction itself where it held (it lies in the
        // same step as the boundary, and moves smoothly from lens to lens), else the step's middle.
        const double found = as_predicted ? guess : r;
        if (near)
            first_step = std::max(1LL, std::min(1LL << 20, (long long)(0.5 * std::fabs(r - guess) / options.tolerance_px)));
        if (near) {
            const double e = found + from_start - (*predicted)[a] - start.at(c, s);
            n12 += c;
            n13 += s;
            n22 += c * c;
            n23 += c * s;
            n33 += s * s;
            n11 += 1;
            r1 += e;
            r2 += e * c;
            r3 += e * s;
            // Cramer's rule on the symmetric 3 x 3 system.
            const double det = n11 * (n22 * n33 - n23 * n23) - n12 * (n12 * n33 - n23 * n13) +
                               n13 * (n12 * n23 - n22 * n13);
            if (det > 0) {
                now.a = start.a + (r1 * (n22 * n33 - n23 * n23) - n12 * (r2 * n33 - n23 * r3) +
                                   n13 * (r2 * n23 - n22 * r3)) / det;
                now.b = start.b + (n11 * (r2 * n33 - n23 * r3) - r1 * (n12 * n33 - n23 * n13) +
                                   n13 * (n12 * r3 - r2 * n13)) / det;
                now.c = start.c + (n11 * (n22 * r3 - r2 * n23) - n12 * (n12 * r3 - r2 * n13) +
                                   r1 * (n12 * n23 - n22 * n13)) / det;
            }
        }
        previous = r;
        if (radii)
            radii->push_back(found + from_start);
        area += 0.5 * r * r * dtheta;
        mu += r * r * r / 3 * c * dtheta;
        mv += r * r * r / 3 * s * dtheta;
    }
    if (change && near)
        *change = now;
    return Moments{area, area * su + mu, area * sv + mv};
}

// Sensor pixel (centre convention, unbounded) of an optics-frame point projected from the exit
// pupil's centre onto the sensor plane.
bool project_to_sensor_px(const PlenopticCamera& m, Vec3 q, Vec2* px)
{
    const Vec3 e = m.lens->exit_pupil_centre();
    if (!(q.z < e.z))
        return false;
    const double t = (m.sensor.z_mm - e.z) / (q.z - e.z);
    const PixelPoint p = m.sensor.to_pixel(e.x + t * (q.x - e.x), e.y + t * (q.y - e.y));
    *px = Vec2{p.u, p.v};
    return is_finite(*px);
}

// Area (pixels^2) of the lens's cell projected from the exit pupil's centre onto the sensor.
double microimage_cell_area_px(const PlenopticCamera& m, LensIndex lens)
{
    Vec2 corners[6];
    const int count = m.array.cell_corners(corners);
    const Vec2 c = m.array.centre_local(lens);
    Vec2 px[6];
    for (int i = 0; i < count; ++i)
        if (!project_to_sensor_px(m, m.array.to_optics(Vec3{c.x + corners[i].x, c.y + corners[i].y, 0}), &px[i]))
            return 0;
    double twice = 0;
    for (int i = 0; i < count; ++i)
        twice += cross(px[i], px[(i + 1) % count]);
    return 0.5 * std::fabs(twice);
}

// Where to look for a lens's microimage at one aperture point: a disc of the sensor (corner-
// convention pixels) that holds it, or nothing when no light passes.
struct Guess {
    bool possible;
    double u, v, radius_px;
    // Where the light towards the disc's centre lands through the lens as it is (a thin lens with a
    // manufacturing error along its axis or a tilt; (u, v) otherwise): the point the region moves
    // with from lens to lens, so that its radii are handed on as seen from it.
    double frame_u, frame_v;
    // How the lens as it is stretches its region about that point against an untilted lens at its
    // place in the array's plane (the derivatives of where light lands, taken through both):
    // sensor offsets map as (stretch[0] stretch[1]; stretch[2] stretch[3]); the identity otherwise.
    double stretch[4];
};

// The disc of the exit pupil's plane through which light from the aperture point h can pass
// (the pupil bounds of a traced lens; the exit pupil of an ideal one), carried back through the
// microlens to the sensor: the ray from h towards point q of that plane came from the sensor
// point h - (h_z - sensor_z) (w' + (h - c) / f), w' = (q - h) / (q_z - h_z) (pinholes: no
// (h - c) / f). Exact for an array parallel to the sensor, a guess otherwise (the bracket grows
// where light reaches farther; for a refracting lens a paraxial guess with a wider bracket). A
// pinhole main lens has no pupil disc: the cell's image then.
Guess guess_region(const PlenopticCamera& m, LensIndex lens, double lens_u, double lens_v, Vec2 lattice_px)
{
    const double pixel = std::min(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1]);
    const double behind = effective_array_distance_mm(m);
    const Vec2 c_local = m.array.centre_local(lens);
    const bool thin = m.array.microlens->forms_image();  // light through the whole cell, bent by f
    const Vec2 offset = thin ? m.array.cell_point(lens_u, lens_v) : Vec2{0, 0};
    const Vec3 h = m.array.to_optics(Vec3{c_local.x + offset.x, c_local.y + offset.y, 0});
    PupilDisc disc{m.lens->exit_pupil_centre(), m.lens->exit_pupil_radius()};
    if (m.pupil_bounds)
        disc = m.pupil_bounds->disc_for(h);
    if (!m.lens->forms_image() || !(disc.radius >= 0)) {
        const double main = effective_main_distance_mm(m);
        const double cell = m.array.cell_circumradius_mm * (main > 0 ? (main + behind) / main : 1);
        return Guess{true, lattice_px.x + 0.5, lattice_px.y + 0.5, 2 * cell / pixel + 2, lattice_px.x + 0.5, lattice_px.y + 0.5, {1, 0, 0, 1}};
    }
    if (disc.radius == 0)
        return Guess{false, 0, 0, 0, 0, 0, {1, 0, 0, 1}};
    const double along = disc.centre.z - h.z, drop = h.z - m.sensor.z_mm;
    if (!(along > 0) || !(drop > 0))
        return Guess{false, 0, 0, 0, 0, 0, {1, 0, 0, 1}};
    double wx = (disc.centre.x - h.x) / along, wy = (disc.centre.y - h.y) / along;
    if (thin) {
        const double f = m.array.focal_length_mm(lens);
        const Vec3 shift = mul(m.array.pose.rotation, Vec3{offset.x / f, offset.y / f, 0});
        wx += shift.x;
        wy += shift.y;
    }
    Guess guess{true, 0, 0, disc.radius * drop / along / pixel, 0, 0, {1, 0, 0, 1}};
    if (thin && !m.array.microlens->first_order_exact()) {
        // A refracting lens: the paraxial guess, with a bracket wider by as far as the lens bends
        // light from the cell's corner (its thickness and spherical aberration move the region by
        // less than that).
        guess.radius_px += m.array.cell_circumradius_mm * drop / m.array.focal_length_mm(lens) / pixel + 2;
    }
    const PixelPoint centre = m.sensor.to_pixel(h.x - drop * wx, h.y - drop * wy);
    guess.u = centre.u;
    guess.v = centre.v;
    guess.u += 0.5;
    guess.v += 0.5;
    guess.frame_u = guess.u;
    guess.frame_v = guess.v;
    const LensFrame frame = m.array.frame(lens);
    if (thin && m.array.microlens->first_order_exact() && (frame.tilted || frame.centre.z != 0)) {
        // The renderer's thin lens run backwards (array/microlens.cpp): the ray leaving the lens's
        // cell point towards `target`, its slopes in the lens's frame less the lens's bend
        // offset / f, is the ray that came from the sensor; where it came from, in pixels.
        auto landing = [&](const LensFrame& lens_frame, Vec3 target, Vec2* px) {
            const Vec3 in_plane{offset.x, offset.y, 0};
            const Vec3 leave =
                m.array.to_optics(lens_frame.centre + (lens_frame.tilted ? mul(lens_frame.axes, in_plane) : in_plane));
            Vec3 out = mul_transposed(m.array.pose.rotation, target - leave);
            if (lens_frame.tilted)
                out = mul_transposed(lens_frame.axes, out);
            if (!(out.z > 0))
                return false;
            Vec3 in{out.x / out.z + offset.x / lens_frame.focal_mm, out.y / out.z + offset.y / lens_frame.focal_mm, 1};
            if (lens_frame.tilted)
                in = mul(lens_frame.axes, in);
            in = mul(m.array.pose.rotation, in);
            if (!(in.z > 0))
                return false;
            const double t = (leave.z - m.sensor.z_mm) / in.z;
            const PixelPoint from = m.sensor.to_pixel(leave.x - t * in.x, leave.y - t * in.y);
            *px = Vec2{from.u + 0.5, from.v + 0.5};
            return std::isfinite(px->x) && std::isfinite(px->y);
        };
        // The same lens untilted in the array's plane.
        LensFrame flat = frame;
        flat.centre.z = 0;
        flat.tilted = false;
        // Targets a fifth of the disc's radius aside, across the light's direction (x, y in the
        // optics frame suffice: the disc lies across the axis).
        const double aside = 0.2 * disc.radius;
        const Vec3 targets[3] = {disc.centre, disc.centre + Vec3{aside, 0, 0}, disc.centre + Vec3{0, aside, 0}};
        Vec2 at[3], ideal[3];
        bool ok = true;
        for (int i = 0; i < 3 && ok; ++i)
            ok = landing(frame, targets[i], &at[i]) && landing(flat, targets[i], &ideal[i]);
        const double j0[4] = {ideal[1].x - ideal[0].x, ideal[2].x - ideal[0].x, ideal[1].y - ideal[0].y,
                              ideal[2].y - ideal[0].y};
        const double det = j0[0] * j0[3] - j0[1] * j0[2];
        if (ok && det != 0) {
            guess.frame_u = at[0].x;
            guess.frame_v = at[0].y;
            // stretch = J J0^-1 (J, J0: the landing points' derivatives through the lens and the flat one).
            const double j[4] = {at[1].x - at[0].x, at[2].x - at[0].x, at[1].y - at[0].y, at[2].y - at[0].y};
            const double inverse[4] = {j0[3] / det, -j0[1] / det, -j0[2] / det, j0[0] / det};
            guess.stretch[0] = j[0] * inverse[0] + j[1] * inverse[2];
            guess.stretch[1] = j[0] * inverse[1] + j[1] * inverse[3];
            guess.stretch[2] = j[2] * inverse[0] + j[3] * inverse[2];
            guess.stretch[3] = j[2] * inverse[1] + j[3] * inverse[3];
        }
    }
    if (!(std::isfinite(guess.u) && std::isfinite(guess.v) && std::isfinite(guess.radius_px)))
        return Guess{false, 0, 0, 0, 0, 0, {1, 0, 0, 1}};
    return guess;
}

// The array-local box (x0, y0, x1, y1) that the picture's corners project to, or false.
bool picture_on_array(const PlenopticCamera& m, double box[4])
{
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    box[0] = box[1] = INFINITY;
    box[2] = box[3] = -INFINITY;
    const double corners[4][2] = {{0, 0}, {double(W), 0}, {0, double(H)}, {double(W), double(H)}};
    for (const auto& corner : corners) {
        Vec2 q;
        if (!project_to_array(m, m.sensor.point(corner[0], corner[1]), &q))
            return false;
        box[0] = std::min(box[0], q.x);
        box[1] = std::min(box[1], q.y);
        box[2] = std::max(box[2], q.x);
        box[3] = std::max(box[3], q.y);
    }
    return true;
}

// A point of the lens's cell at which its light is measured, as the renderer's aperture sample
// (lens_u, lens_v), and the share of the cell it stands for (1 / divisor).
struct CellNode {
    double lens_u, lens_v, divisor;
};

// The cell points at which a lens's light is measured: the midpoint rule on the renderer's own
// uniform map of the cell, aperture_points a side (refracting lenses: at least
// refracting_points, as their regions differ from point to point); pinholes: the centre.
std::vector<CellNode> cell_nodes(const PlenopticCamera& m, const MicroimageOptions& options)
{
    std::vector<CellNode> nodes;
    if (!m.array.microlens->forms_image()) {
        nodes.push_back(CellNode{0.5, 0.5, 1});
        return nodes;
    }
    const int n = std::max(1, m.array.microlens->first_order_exact()
                                  ? options.aperture_points
                                  : std::max(options.aperture_points, options.refracting_points));
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            nodes.push_back(CellNode{(i + 0.5) / n, (j + 0.5) / n, double(n * n)});
    return nodes;
}

// Refracting microlenses on an array with displaced lenses: the renderer samples a lens's cell (the
// lattice's cell shape about the lens's actual centre, in the lens's own plane) and passes only the
// points that lie in the lens's own cell, nearer its actual centre than any neighbour's
// (array/refracting_microlens.cpp). The light comes through the part of the cell that does: a
// convex polygon about the centre, the cell cut by the bisectors with the displaced neighbours.
// Leaving out the cell points that fall outside it would count whole points in or out, a step of
// a 576th of the light each (up to some 0.04 px where the microimages fill their cells, BENCHMARKS
// "Cell points on displaced lenses"). Instead each cell point h moves along its ray from the centre
// by the cut polygon's radius over the cell's there, s = rho_cut / rho_cell <= 1, and weighs s^2
// more (the map (r, theta) -> (s(theta) r, theta) scales areas by s^2): the same midpoint rule on
// the cut cell, whose integrand bends where the polygon turns but no longer steps. Returns whether
// any point moved (the nodes are `nodes` themselves otherwise).
bool nodes_in_own_cell(const MicrolensArray& a, LensIndex lens, const std::vector<CellNode>& nodes,
                       std::vector<CellNode>* out)
{
    const LensFrame frame = a.frame(lens);
    // A cell point h (the lens's plane) lies at frame.centre + axes h (the array's frame), on the
    // lens's side of the bisector with neighbour n when (axes h) . delta <= |delta|^2 / 2, delta =
    // its centre less this one (in the plane), that is h . delta' <= |delta|^2 / 2 with delta' the
    // plane part of axes^T delta. (Every displacement is below a quarter of the pitch, so only the
    // adjacent lenses' bisectors can cut the cell: MicrolensArray::nearest.)
    LensIndex adjacent[8];
    const int count = adjacent_lenses(a.grid, lens, adjacent);
    Vec2 normal[8];
    double half_sq[8];
    for (int j = 0; j < count; ++j) {
        const Vec3 c = a.centre_local3(adjacent[j]);
        const Vec3 delta{c.x - frame.centre.x, c.y - frame.centre.y, 0};
        const Vec3 in_plane = frame.tilted ? mul_transposed(frame.axes, delta) : delta;
        normal[j] = Vec2{in_plane.x, in_plane.y};
        half_sq[j] = 0.5 * (delta.x * delta.x + delta.y * delta.y);
    }
    auto own = [&](Vec2 h) {
        const Vec3 in_plane{h.x, h.y, 0};
        const Vec3 local = frame.centre + (frame.tilted ? mul(frame.axes, in_plane) : in_plane);
        return a.nearest(local.x, local.y) == lens;
    };
    bool moved = false;
    out->assign(nodes.begin(), nodes.end());
    for (CellNode& node : *out) {
        const Vec2 h = a.cell_point(node.lens_u, node.lens_v);
        const double ring = cell_ring(a.grid, a.pitch_mm, h);
        double scale = 1;
        for (int j = 0; j < count; ++j) {
            const double along = h.x * normal[j].x + h.y * normal[j].y;
            if (along > 0)
                scale = std::min(scale, ring * half_sq[j] / along);
        }
        if (!(scale < 1))
            continue;
        // The moved point as the renderer will make it from its sample, inside the lens's own cell
        // (a point on the polygon's edge may round to the neighbour's side: moved in a hair).
        Vec2 sample{node.lens_u, node.lens_v};
        for (int attempt = 0; attempt < 4; ++attempt) {
            sample = cell_uniform_inverse(a.grid, a.pitch_mm, Vec2{scale * h.x, scale * h.y});
            if (own(a.cell_point(sample.x, sample.y)))
                break;
            scale *= 1 - 1e-9;
        }
        node.lens_u = sample.x;
        node.lens_v = sample.y;
        node.divisor /= scale * scale;
        moved = true;
    }
    return moved;
}

} // namespace

MicroimageOptions default_microimage_options()
{
    MicroimageOptions options;
    options.azimuths = 32;
    options.tolerance_px = 1e-3;
    options.aperture_points = 3;
    options.threads = 0;
    options.reuse_neighbours = true;
    options.anchor_step = 16;
    options.refracting_points = 24;
    return options;
}

namespace {

// One lens's microimage measured through `light`'s rays (its lens and start points `m`'s), cell
// point by cell point, each region's radii sought near a prediction where there is one.
class LensMeasurer {
public:
    // Per cell point, the radii of its region in the last kHistory lenses measured with it, newest
    // first (fewer at a run's start or after a lens without that region), and a prediction.
    struct Radii {
        std::vector<std::vector<std::vector<double>>> history;
        std::vector<double> predicted, now;
    };
    static const std::size_t kHistory = 2;

    LensMeasurer(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options)
        : m_(m), light_(light), options_(options), all_nodes_(cell_nodes(m, options)),
          // Refracting lenses that may be displaced: each lens's cell points moved into its own cell.
          cut_cells_(light.array.errors && light.array.errors->max_shift_mm() > 0 &&
                     refracting_shape(*light.array.microlens) != nullptr)
    {
    }

    // Radii with no history, for this measurer's cell points.
    Radii fresh() const
    {
        Radii radii;
        radii.history.resize(all_nodes_.size());
        return radii;
    }

    // Measures truth.lens; `radii` (if given) predicts each region from its history and takes this
    // lens's radii into it; `own_nodes` is scratch. `lobe` (if given): whether a region of the
    // microimage is a lobe of light that crossed cells (region_moments).
    void measure(MicroimageTruth& truth, Radii* radii, std::vector<CellNode>* own_nodes, bool* lobe_out) const
    {
        const std::vector<CellNode>& nodes =
            cut_cells_ && nodes_in_own_cell(light_.array, truth.lens, all_nodes_, own_nodes) ? *own_nodes : all_nodes_;
        bool found_lobe = false;
        const MicroimageCentre lattice = microimage_centre_px(m_, truth.lens);
        const Vec2 centre{lattice.u, lattice.v};
        Moments total{0, 0, 0};
        RadiusChange change;  // of this lens's regions from their predictions
        for (std::size_t point = 0; point < nodes.size(); ++point) {
            const CellNode& node = nodes[point];
            std::vector<double>* now = radii ? &radii->now : nullptr;
            const std::vector<double>* predicted = nullptr;
            if (radii) {
                // The last radii moved by their mean change per lens over the history.
                now->clear();
                const std::vector<std::vector<double>>& past = radii->history[point];
                if (!past.empty()) {
                    const std::size_t h = past.size();
                    radii->predicted = past[0];
                    for (std::size_t a = 0; h > 1 && a < past[0].size(); ++a)
                        radii->predicted[a] += (past[0][a] - past[h - 1][a]) / double(h - 1);
                    predicted = &radii->predicted;
                }
            }
            const Guess guess = guess_region(light_, truth.lens, node.lens_u, node.lens_v, centre);
            if (!guess.possible) {
                if (radii)
                    radii->history[point].clear();
                continue;
            }
            const LensProbe probe(light_, truth.lens, node.lens_u, node.lens_v);
            // A start point anywhere in the disc is at most its diameter from the boundary.
            const double search = guess.radius_px + 1, reach = 2.1 * guess.radius_px + 1;
            // Radii are handed from lens to lens as seen from where the guess's central ray lands: it
            // moves with the lens's own position, focal length and tilt (manufacturing errors), so that
            // what is left to predict from the neighbours is how the main lens's light changes across
            // the field.
            const Vec2 reference{guess.frame_u, guess.frame_v};
            // Radii are handed on as an untilted lens in the array's plane would give them: a radius
            // along u = (cos, sin) of this lens is that one's times u . stretch u.
            const double* st = guess.stretch;
            const bool stretched = st[0] != 1 || st[1] != 0 || st[2] != 0 || st[3] != 1;
            auto stretch_along = [&](int a) {
                const double theta = 2 * kPi * a / options_.azimuths, c = std::cos(theta), s = std::sin(theta);
                return c * (st[0] * c + st[1] * s) + s * (st[2] * c + st[3] * s);
            };
            if (predicted && stretched)
                for (std::size_t a = 0; a < radii->predicted.size(); ++a)
                    radii->predicted[a] *= stretch_along(int(a));
            bool lobe = false;
            const Moments region =
                region_moments(probe, guess.u, guess.v, search, reach, options_, reference, predicted, &change, now,
                               lobe_out ? &lobe : nullptr);
            found_lobe = found_lobe || (lobe && region.area > 0);
            if (radii && stretched)
                for (std::size_t a = 0; a < now->size(); ++a)
                    (*now)[a] /= stretch_along(int(a));
            if (radii) {
                std::vector<std::vector<double>>& past = radii->history[point];
                if (now->empty()) {
                    past.clear();
                } else {
                    if (past.size() < kHistory)
                        past.push_back(std::vector<double>());
                    for (std::size_t age = past.size() - 1; age > 0; --age)
                        std::swap(past[age], past[age - 1]);
                    std::swap(past[0], *now);
                }
            }
            total.area += region.area / node.divisor;
            total.mu += region.mu / node.divisor;
            total.mv += region.mv / node.divisor;
        }
        truth.lit = total.area > 0;
        truth.u_px = truth.lit ? total.mu / total.area - 0.5 : 0;
        truth.v_px = truth.lit ? total.mv / total.area - 0.5 : 0;
        const double cell = microimage_cell_area_px(m_, truth.lens);
        truth.lit_fraction = cell > 0 ? total.area / cell : 0;
        if (lobe_out)
            *lobe_out = found_lobe;
    }

private:
    const PlenopticCamera& m_;
    const PlenopticCamera& light_;
    const MicroimageOptions& options_;
    const std::vector<CellNode> all_nodes_;
    const bool cut_cells_;
};

// Measures the lenses of `out` (their `lens` set, row by row), each through `light`'s rays; a run
// of neighbours is lenses k, k + step, k + 2 step, ... of one row. Reports (now, out.size()) about
// every tenth of the lenses; false when `cancelled` stopped it. `lobes` (if given): per lens,
// whether a region of its microimage is a lobe of light that crossed cells (region_moments).
bool measure_lenses(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options,
                    std::vector<MicroimageTruth>& out, std::int64_t step, const MicroimageProgress& progress,
                    const MicroimageCancel& cancelled, std::vector<char>* lobes = nullptr)
{
    if (out.empty())
        return true;
    const LensMeasurer measurer(m, light, options);
    typedef LensMeasurer::Radii Radii;
    if (lobes)
        lobes->assign(out.size(), 0);
    auto measure = [&](std::size_t index, Radii* radii, std::vector<CellNode>* own_nodes) {
        bool lobe = false;
        measurer.measure(out[index], radii, own_nodes, lobes ? &lobe : nullptr);
        if (lobes)
            (*lobes)[index] = lobe;
    };

    // Runs of up to kRun neighbouring lenses of one row (k, k + 1, ...): the first lens of a run is
    // measured from scratch, each next one near the one before (its boundary moves little from lens
    // to lens). Runs are fixed by the lenses alone and handed out one at a time to the threads, each
    // result in its own slot, so the output does not depend on the thread count.
    const std::size_t kRun = 256;
    std::vector<std::size_t> runs;  // the first lens of each run, then out.size()
    for (std::size_t i = 0; i < out.size(); ++i)
        if (i == 0 || i - runs.back() >= kRun || out[i].lens.l != out[i - 1].lens.l ||
            out[i].lens.k != out[i - 1].lens.k + step)
            runs.push_back(i);
    runs.push_back(out.size());
    const bool reuse = options.reuse_neighbours;
    std::atomic<std::size_t> next(0), done(0);
    std::atomic<bool> stop(false);
    std::size_t reported = 0;
    // The calling thread (`reports`) works too: it polls `cancelled` between lenses and reports.
    auto work = [&](bool reports) {
        Radii radii = measurer.fresh();
        std::vector<CellNode> own_nodes;
        for (std::size_t r = next++; r + 1 < runs.size() && !stop; r = next++) {
            for (std::vector<std::vector<double>>& past : radii.history)
                past.clear();
            for (std::size_t i = runs[r]; i < runs[r + 1] && !stop; ++i) {
                if (reports && cancelled && cancelled()) {
                    stop = true;
                    break;
                }
                measure(i, reuse ? &radii : nullptr, &own_nodes);
                const std::size_t now = ++done;
                if (reports && progress && now * 10 / out.size() > reported * 10 / out.size()) {
                    reported = now;
                    progress(now, out.size());
                }
            }
        }
    };
    const unsigned hardware = std::thread::hardware_concurrency();
    const int threads = options.threads > 0 ? options.threads : int(std::max(1u, hardware));
    std::vector<std::thread> workers;
    for (int t = 1; t < threads && std::size_t(t) + 1 < runs.size(); ++t)
        workers.push_back(std::thread(work, false));
    work(true);
    for (std::thread& worker : workers)
        worker.join();
    return !stop;
}

// The camera's symmetry about its optical axis, where the truth uses it: refracting microlenses (the
// costly ones, measured at refracting_points^2 cell points) on an ideal array (no manufacturing
// errors, not tilted, one kind of lens) whose lens (0, 0) sits on the axis, on a hexagonal or square
// lattice, its rows along the sensor's x or y axis. The main lens is symmetric about its axis (every
// model is), and so are the sensor's and the array's planes; the lattice with its cells is symmetric
// under the mirrors in the array's x and y axes through lens (0, 0). Each mirror maps the camera onto itself, lens onto lens, and the
// light through a lens onto the light through its image; and the truth's own rule is symmetric
// under the same mirrors (its cell points, the renderer's map of the cell, and its directions from
// the start point, 0 and 90 degrees among them; its start point is the mirrored guess, or the
// centroid of a coarse grid centred on it). So a lens's microimage is its mirror image's, mirrored:
// only the lenses of the quarter x >= 0, y >= 0 of the array's frame are measured, and every other
// lens takes the microimage of its image there, mirrored (centroid; the lit fraction as it is). The
// lattice's turns by 60 degrees and its mirrors in lines between the axes are symmetries of the
// camera too, but not of the rule (a lens and its image under them, each measured, differ by the
// rule's own error, some 1e-3 px): used, they would put steps of that size into the truth where a
// lens and its neighbour would take their microimages from lenses measured apart.
class Symmetry {
public:
    Symmetry(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options)
    {
        const MicrolensArray& a = m.array;
        valid_ = options.symmetry && a.microlens && a.microlens->forms_image() && !a.microlens->first_order_exact() &&
                 !a.errors && !light.array.errors &&
                 (a.grid == GridType::Hexagonal || a.grid == GridType::Rectangular) && !a.pose.tilted &&
                 !light.array.pose.tilted && a.lens_type_count == 1 && a.pose.centre_mm.x == 0 &&
                 a.pose.centre_mm.y == 0 && light.array.pose.centre_mm.x == 0 && light.array.pose.centre_mm.y == 0;
        // The array's turn about the axis (its rows' direction in the optics frame): a multiple of 90
        // degrees (exact: array/microlens_array.h), so that its mirrors are the sensor's, under which
        // the rule's coarse grids and directions, laid out in pixels, are symmetric too.
        const Vec3 x = mul(a.pose.rotation, Vec3{1, 0, 0});
        frame_[0] = x.x;
        frame_[1] = x.y;
        valid_ = valid_ && (frame_[0] == 0 || frame_[1] == 0);
    }
    bool valid() const { return valid_; }

    // The lens of the quarter x >= 0, y >= 0 whose mirror image `lens` is, and the mirrors that map
    // it there (x -> -x, y -> -y).
    static LensIndex quarter_lens(const MicrolensArray& a, LensIndex lens, bool* mirror_x, bool* mirror_y)
    {
        const Vec2 c = a.lattice_centre_local(lens);
        *mirror_x = c.x < 0;
        *mirror_y = c.y < 0;
        if (!*mirror_x && !*mirror_y)
            return lens;
        return a.nearest(std::fabs(c.x), std::fabs(c.y));  // a lattice point: the lattice is symmetric
    }

    // A sensor point (centre-convention pixels) of the quarter lens's microimage, mirrored.
    Vec2 map_px(const Sensor& sensor, bool mirror_x, bool mirror_y, Vec2 px) const
    {
        const Vec3 p = sensor.point(px.x + 0.5, px.y + 0.5);
        // Into the array's frame (a turn about the axis), mirrored, and back.
        Vec2 q{frame_[0] * p.x + frame_[1] * p.y, -frame_[1] * p.x + frame_[0] * p.y};
        if (mirror_x)
            q.x = -q.x;
        if (mirror_y)
            q.y = -q.y;
        const PixelPoint out = sensor.to_pixel(frame_[0] * q.x - frame_[1] * q.y, frame_[1] * q.x + frame_[0] * q.y);
        return Vec2{out.u, out.v};
    }

private:
    bool valid_ = false;
    double frame_[2] = {1, 0};  // cos, sin of the array's turn
};

// A lens as a key of the maps of measured lenses.
std::uint64_t anchor_key(LensIndex lens)
{
    return (std::uint64_t(lens.k) << 32) ^ (std::uint64_t(lens.l) & 0xffffffffull);
}

// Lenses in the order measure_lenses takes them: row by row (l, then k, increasing).
void sort_row_by_row(std::vector<MicroimageTruth>& lenses)
{
    std::sort(lenses.begin(), lenses.end(), [](const MicroimageTruth& p, const MicroimageTruth& q) {
        return p.lens.l != q.lens.l ? p.lens.l < q.lens.l : p.lens.k < q.lens.k;
    });
}

// measure_lenses, with the camera's symmetry where it holds: each lens of `out` takes the microimage
// of its quarter lens, those measured once each (and kept in `cache`, by lens, for later calls).
bool measure_symmetric(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options,
                       std::vector<MicroimageTruth>& out, std::int64_t step, const MicroimageProgress& progress,
                       const MicroimageCancel& cancelled, std::vector<char>* lobes,
                       std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>>* cache)
{
    const Symmetry symmetry(m, light, options);
    if (!symmetry.valid())
        return measure_lenses(m, light, options, out, step, progress, cancelled, lobes);
    std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>> local;
    std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>>& known = cache ? *cache : local;
    struct Map {
        LensIndex quarter;
        bool mirror_x, mirror_y;
    };
    std::vector<Map> maps(out.size());
    std::vector<MicroimageTruth> wanted;
    {
        std::unordered_map<std::uint64_t, char> seen;
        for (std::size_t i = 0; i < out.size(); ++i) {
            Map& map = maps[i];
            map.quarter = Symmetry::quarter_lens(m.array, out[i].lens, &map.mirror_x, &map.mirror_y);
            const std::uint64_t k = anchor_key(map.quarter);
            if (known.count(k) == 0 && seen.emplace(k, 1).second) {
                MicroimageTruth t = MicroimageTruth();
                t.lens = map.quarter;
                wanted.push_back(t);
            }
        }
    }
    sort_row_by_row(wanted);
    std::vector<char> wanted_lobes;
    // (The quarter lenses of lenses `step` apart along rows are `step` apart too: anchors of a level.)
    if (!measure_lenses(m, light, options, wanted, step, progress, cancelled, &wanted_lobes))
        return false;
    for (std::size_t i = 0; i < wanted.size(); ++i)
        known[anchor_key(wanted[i].lens)] = std::make_pair(wanted[i], wanted_lobes[i]);
    if (lobes)
        lobes->assign(out.size(), 0);
    for (std::size_t i = 0; i < out.size(); ++i) {
        const std::pair<MicroimageTruth, char>& found = known.at(anchor_key(maps[i].quarter));
        const LensIndex lens = out[i].lens;
        out[i] = found.first;
        out[i].lens = lens;
        if (out[i].lit) {
            const Vec2 c = symmetry.map_px(m.sensor, maps[i].mirror_x, maps[i].mirror_y,
                                           Vec2{found.first.u_px, found.first.v_px});
            out[i].u_px = c.x;
            out[i].v_px = c.y;
        }
        if (lobes)
            (*lobes)[i] = found.second;
    }
    return true;
}

// Refracting microlenses on an ideal array: every lens of the array sees its own part of the main
// lens's light through the same glass, so its microimage's offset from its lattice centre and its
// lit fraction are smooth functions of where the lens is. Those lenses are measured exactly at
// anchors, every anchor_step-th lens of every anchor_step-th row, and interpolated between them
// (a cubic in each direction, on the 4 x 4 anchors nearest the lens), wherever the anchors say the
// cubic holds; the other lenses are measured. A lens's position in lattice units: X = k (+ 1/2 on
// the odd rows of a hexagonal array), Y = l. (The anchors' grid is symmetric under the mirrors of
// Symmetry: an anchor's quarter lens is an anchor.)
double lattice_x(GridType grid, LensIndex lens)
{
    return double(lens.k) + (grid == GridType::Hexagonal && floor_mod(lens.l, 2) == 1 ? 0.5 : 0.0);
}

// The cubic through four anchors at 0, 1, 2, 3, at t: its weights.
void cubic_weights(double t, double w[4])
{
    w[0] = -(t - 1) * (t - 2) * (t - 3) / 6;
    w[1] = t * (t - 2) * (t - 3) / 2;
    w[2] = -t * (t - 1) * (t - 3) / 2;
    w[3] = t * (t - 1) * (t - 2) / 6;
}

// The cubic's error, from fourth differences of the anchors: the cubic through four points at unit
// steps misses a function by f''''(xi) / 24 |t (t - 1) (t - 2) (t - 3)| at t (at most 0.023 f''''
// between the middle two, 0.042 between the outer ones at the array's edge), and f'''' is about the
// fourth difference of five anchors, the larger of the two windows that hold the four; the error of
// the two directions' cubics add. kCubicMargin on that estimate.
const double kCubicMargin = 1.5;
double cubic_error(double t, double fourth_difference)
{
    return kCubicMargin * std::fabs(t * (t - 1) * (t - 2) * (t - 3)) / 24 * fourth_difference;
}
// The interpolation is used where that estimate is below these, half the accuracy the truth keeps (0.001 px, 1e-4 of lit fraction): the measured lenses themselves scatter about a
// smooth field by some 1e-4 px and 3e-5 of lit fraction (small regions near the cell's edge found or
// missed, the cell's band cut differently by the 24 x 24 cell points from lens to lens), which the
// interpolation does not follow, and which gives fourth differences of up to about 1.5e-3 px and
// 3e-4 where the field itself is smooth.
const double kInterpolatedPx = 5e-4;
const double kInterpolatedFraction = 5e-5;

// One anchor: its lens's offset from its lattice centre (pixels) and its lit fraction.
struct AnchorValue {
    bool lit;
    double value[3];  // du, dv, lit fraction
    // A region of its microimage is a lobe of light that crossed into a neighbour's column
    // (region_moments).
    bool lobe;
};

// The anchors of one level: lenses (K step, L step), K = k0 .. k1, L = l0 .. l1, those measured
// in `values`.
struct Anchors {
    std::int64_t step = 0, k0 = 0, k1 = 0, l0 = 0, l1 = 0;
    const std::unordered_map<std::uint64_t, AnchorValue>* values = nullptr;

    // The first anchor (i0, j0) of the 4 x 4 of a lens at `at` (lattice units: X, Y above), and where
    // it lies in anchor units.
    void stencil(Vec2 at, std::int64_t* i0, std::int64_t* j0, double* x, double* y) const
    {
        *x = at.x / double(step);
        *y = at.y / double(step);
        *i0 = std::max(k0, std::min(k1 - 3, std::int64_t(std::floor(*x)) - 1));
        *j0 = std::max(l0, std::min(l1 - 3, std::int64_t(std::floor(*y)) - 1));
    }
    // Calls f(K, L) for each anchor the lens's interpolation reads: its 4 x 4 and the anchors one
    // beyond them along its rows and columns (for the fourth differences), inside the range.
    template <class F> void each(std::int64_t i0, std::int64_t j0, F f) const
    {
        for (std::int64_t j = std::max(l0, j0 - 1); j <= std::min(l1, j0 + 4); ++j)
            for (std::int64_t i = std::max(k0, i0 - 1); i <= std::min(k1, i0 + 4); ++i)
                if ((j >= j0 && j <= j0 + 3) || (i >= i0 && i <= i0 + 3))
                    f(i, j);
    }
    LensIndex lens(std::int64_t K, std::int64_t L) const { return LensIndex{K * step, L * step}; }

    // Anchors `s` lenses apart over lenses whose positions run from range[0] to range[1] (X) and
    // range[2] to range[3] (Y): one more below and two more above, so that every stencil fits.
    void cover(std::int64_t s, const double range[4])
    {
        step = s;
        k0 = std::int64_t(std::floor(range[0] / double(s))) - 1;
        k1 = std::int64_t(std::floor(range[1] / double(s))) + 2;
        l0 = std::int64_t(std::floor(range[2] / double(s))) - 1;
        l1 = std::int64_t(std::floor(range[3] / double(s))) + 2;
    }
    // At least five anchors a side (the fourth differences need them).
    bool enough() const { return k1 - k0 >= 4 && l1 - l0 >= 4; }
    // The anchors that the lenses `lenses` (indices into `at`, their positions) read, once each and
    // in the order first read, those for which known(key) is false, as truths with the lens set.
    template <class Known>
    std::vector<MicroimageTruth> read_by(const std::vector<std::size_t>& lenses, const std::vector<Vec2>& at,
                                         const Known& known) const
    {
        std::vector<MicroimageTruth> read;
        std::unordered_map<std::uint64_t, char> seen;
        for (std::size_t index : lenses) {
            std::int64_t i0, j0;
            double x, y;
            stencil(at[index], &i0, &j0, &x, &y);
            each(i0, j0, [&](std::int64_t i, std::int64_t j) {
                const LensIndex anchor = lens(i, j);
                const std::uint64_t key = anchor_key(anchor);
                if (!known(key) && seen.emplace(key, 1).second) {
                    MicroimageTruth t = MicroimageTruth();
                    t.lens = anchor;
                    read.push_back(t);
                }
            });
        }
        return read;
    }
};

// The cubic through the 4 x 4 anchors from (i0, j0) (Anchors::stencil) of the value v(i, j, q), at
// (x, y) in anchor units, and in `error` the estimate of how far it misses the function: each
// direction's cubic_error from the largest fourth difference along it over the stencil's rows and
// columns, of each window of five anchors that holds the stencil's four (every anchor of
// Anchors::each is read).
template <class V>
double cubic_through(const Anchors& a, std::int64_t i0, std::int64_t j0, double x, double y, const V& v, int q,
                     double* error)
{
    double largest[2] = {0, 0};
    for (int across = 0; across < 4; ++across)
        for (std::int64_t first = -1; first <= 0; ++first) {
            if (i0 + first >= a.k0 && i0 + first + 4 <= a.k1) {
                const std::int64_t i = i0 + first, j = j0 + across;
                const double d4 =
                    v(i, j, q) - 4 * v(i + 1, j, q) + 6 * v(i + 2, j, q) - 4 * v(i + 3, j, q) + v(i + 4, j, q);
                largest[0] = std::max(largest[0], std::fabs(d4));
            }
            if (j0 + first >= a.l0 && j0 + first + 4 <= a.l1) {
                const std::int64_t i = i0 + across, j = j0 + first;
                const double d4 =
                    v(i, j, q) - 4 * v(i, j + 1, q) + 6 * v(i, j + 2, q) - 4 * v(i, j + 3, q) + v(i, j + 4, q);
                largest[1] = std::max(largest[1], std::fabs(d4));
            }
        }
    *error = cubic_error(x - double(i0), largest[0]) + cubic_error(y - double(j0), largest[1]);
    double wx[4], wy[4];
    cubic_weights(x - double(i0), wx);
    cubic_weights(y - double(j0), wy);
    double sum = 0;
    for (int j = 0; j < 4; ++j) {
        double row = 0;
        for (int i = 0; i < 4; ++i)
            row += wx[i] * v(i0 + i, j0 + j, q);
        sum += wy[j] * row;
    }
    return sum;
}

// The lens's microimage from the anchors, or false where the anchors do not vouch for the cubic (a
// dark anchor among those it reads, an anchor with a lobe of light that crossed cells, or a fourth
// difference too large). Lobes (refracting lenses without baffles, light that left its cell in
// the glass and then a neighbour's cap): thin regions apart from the lens's own light, counted
// only at the cell points whose own light is gone (each moved the centre by about 1e-3 px in the
// unit test); where a row of the 24 x 24 cell points begins to count them the centre steps by
// several thousandths of a pixel from one lens to the next (a step between anchors, which neither
// the cubic nor its fourth differences see), so lenses whose anchors count any are measured.
bool interpolate(const Anchors& a, Vec2 at, MicroimageTruth* truth, Vec2 lattice_px)
{
    std::int64_t i0, j0;
    double x, y;
    a.stencil(at, &i0, &j0, &x, &y);
    // The anchors it reads, in a 6 x 6 block from (i0 - 1, j0 - 1); null where not read.
    const AnchorValue* block[6][6] = {};
    bool dark = false;
    bool lobe = false;
    a.each(i0, j0, [&](std::int64_t i, std::int64_t j) {
        const auto found = a.values->find(anchor_key(a.lens(i, j)));
        if (found == a.values->end() || !found->second.lit) {
            dark = true;
        } else {
            block[j - j0 + 1][i - i0 + 1] = &found->second;
            lobe = lobe || found->second.lobe;
        }
    });
    if (dark || lobe)
        return false;
    auto v = [&](std::int64_t i, std::int64_t j, int q) { return block[j - j0 + 1][i - i0 + 1]->value[q]; };
    const double allowed[3] = {kInterpolatedPx, kInterpolatedPx, kInterpolatedFraction};
    double result[3];
    for (int q = 0; q < 3; ++q) {
        double error;
        result[q] = cubic_through(a, i0, j0, x, y, v, q, &error);
        if (error > allowed[q])
            return false;
    }
    truth->lit = true;
    truth->u_px = lattice_px.x + result[0];
    truth->v_px = lattice_px.y + result[1];
    truth->lit_fraction = result[2];
    return true;
}

// Whether the truth interpolates between anchors: refracting microlenses (measured at 24 x 24
// cell points, 64 times a thin lens's cost) on an array without manufacturing errors.
bool interpolates(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options)
{
    return options.anchor_step >= 4 && options.anchor_step % 2 == 0 && m.array.microlens &&
           m.array.microlens->forms_image() && !m.array.microlens->first_order_exact() && !m.array.errors &&
           !light.array.errors && (m.array.grid == GridType::Hexagonal || m.array.grid == GridType::Rectangular);
}

// Where the anchors are measured, and where a lens lies among them. Usually the camera itself, a
// lens at its lattice point. An ideal refracting array turned about the optical axis by other
// than a multiple of 90 degrees, or whose lens (0, 0) is off the axis, has no mirror symmetry; but
// the main lens and the sensor's plane are symmetric under every turn about the axis (every model
// is), so a lens's microimage is, turned, that of the same lens of the array turned back and moved
// onto the axis (its canonical pose), where Symmetry holds. The anchors are then measured in that
// array, and each lens interpolated at the point it occupies there (between lattice points: the
// cubic is a smooth function of position, as the microimage is of where the lens is), then turned
// back with the array. The rule's cell points turn with the array, its directions do not (they are
// laid out in pixels), so the answers are those of the same rule in a turned frame: the same
// accuracy, not the same bits (BENCHMARKS "The microimage truth by symmetry").
class Canonical {
public:
    Canonical(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options)
        : m_(m), light_(light)
    {
        const ArrayPose& pose = m.array.pose;
        const bool about_axis = pose.normal.x == 0 && pose.normal.y == 0 && pose.normal.z == 1 && !pose.tilted;
        auto equal = [](Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
        const bool same = equal(light.array.pose.centre_mm, pose.centre_mm) &&
                          equal(light.array.pose.normal, pose.normal) &&
                          equal(mul(light.array.pose.rotation, Vec3{1, 0, 0}), mul(pose.rotation, Vec3{1, 0, 0}));
        if (!options.symmetry || !about_axis || !same || Symmetry(m, light, options).valid())
            return;
        const double none[3] = {0, 0, 0};
        const ArrayPose canonical = make_array_pose(none, Vec3{0, 0, pose.centre_mm.z});
        model_ = m;
        model_.array.pose = canonical;
        light_model_ = light;
        light_model_.array.pose = canonical;
        if (!Symmetry(model_, light_model_, options).valid())
            return;
        const Vec3 x = mul(pose.rotation, Vec3{1, 0, 0});
        turn_[0] = x.x;
        turn_[1] = x.y;
        active_ = true;
    }
    bool active() const { return active_; }
    // The cameras the anchors are measured in.
    const PlenopticCamera& model() const { return active_ ? model_ : m_; }
    const PlenopticCamera& light() const { return active_ ? light_model_ : light_; }
    // Where the lens lies among those anchors, in lattice units (X, Y above); `shift` (array-local,
    // mm) moves it off its lattice point (a displaced lens: the ideal lens that sits where it sits).
    Vec2 position(LensIndex lens, Vec2 shift = Vec2{0, 0}) const
    {
        if (!active_ && shift.x == 0 && shift.y == 0)
            return Vec2{lattice_x(m_.array.grid, lens), double(lens.l)};
        const Vec2 c = canonical_local(lens, shift);
        return Vec2{c.x / m_.array.pitch_mm, c.y / m_.array.row_spacing_mm()};
    }
    // The lens's lattice centre (moved by `shift`) projected onto the sensor from the exit pupil's
    // centre (pixels, centre convention) in the anchors' camera: what the interpolated offset is
    // added to.
    bool centre_px(LensIndex lens, Vec2* px, Vec2 shift = Vec2{0, 0}) const
    {
        if (!active_ && shift.x == 0 && shift.y == 0) {
            const MicroimageCentre c = microimage_centre_px(m_, lens);
            *px = Vec2{c.u, c.v};
            return c.valid;
        }
        const Vec2 c = canonical_local(lens, shift);
        return project_to_sensor_px(model(), model().array.to_optics(Vec3{c.x, c.y, 0}), px);
    }
    // A sensor point of the anchors' camera (pixels, centre convention) in this camera: turned
    // about the axis with the array.
    Vec2 to_camera_px(Vec2 px) const
    {
        if (!active_)
            return px;
        const Vec3 p = m_.sensor.point(px.x + 0.5, px.y + 0.5);
        const PixelPoint out = m_.sensor.to_pixel(turn_[0] * p.x - turn_[1] * p.y, turn_[1] * p.x + turn_[0] * p.y);
        return Vec2{out.u, out.v};
    }

private:
    // The lens's lattice point in the canonical array's frame: its place in the optics frame turned
    // back about the axis.
    Vec2 canonical_local(LensIndex lens, Vec2 shift) const
    {
        const Vec2 c = m_.array.lattice_centre_local(lens);
        if (!active_)
            return Vec2{c.x + shift.x, c.y + shift.y};
        const Vec3 q = m_.array.to_optics(Vec3{c.x + shift.x, c.y + shift.y, 0});
        return Vec2{turn_[0] * q.x + turn_[1] * q.y, -turn_[1] * q.x + turn_[0] * q.y};
    }

    const PlenopticCamera& m_;
    const PlenopticCamera& light_;
    PlenopticCamera model_, light_model_;
    bool active_ = false;
    double turn_[2] = {1, 0};  // cos, sin of the array's turn about the axis
};

// Manufacturing errors on refracting microlenses, corrected (MicroimageOptions::error_anchor_step;
// renders measure every lens). Measuring each lens costs some 60 ms (its 24 x 24 cell points), hours
// for a raw; but the errors are small (a fraction of a micrometre, a few per cent, a fraction of a
// degree) and a lens's microimage changes smoothly with most of them. So a lens with errors is
// taken as the ideal lens that sits where it sits (the anchors' cubic at its displaced centre: its
// cell and its neighbours moved with it), corrected to second order in each of its parameters x_p:
// its displacement along the axis, its focal factor less 1, its axis's x and y, and each adjacent
// lens's displacement from it (x and y, array frame: where the walls between their columns and the
// bisector that cuts its cell lie). The correction is the sum over p of J_p x_p + H_p x_p^2 / 2 +
// K_p x_p x_f (x_f the focal factor's), J_p, H_p and K_p the central, second and mixed differences
// of Jacobian anchors error_anchor_step lenses apart, each measured with x_p = +h_p and -h_p alone
// (h_p the largest |x_p| the errors give; a lens's own for a displacement), and with x_p = h_p and
// x_f = +-h_f; the corrections the 4 x 4 Jacobian anchors nearest the lens give for its x are
// interpolated by the cubic where their fourth differences vouch for it. Left out: terms in two
// parameters together other than with the focal factor (two neighbours: some 0.005 px), and kinks
// where a neighbour's approach cuts lit cell points and its retreat adds none (BENCHMARKS
// "Refracting microlenses with errors, corrected"). A lens that this cannot vouch for is measured.

// The corrections' cubic is used where its estimated error is below these. The differences carry
// the measurements' own scatter (some 1e-4 to 1e-3 px, 3e-5 of lit fraction, BENCHMARKS "Refracting
// microlenses between anchors") divided by the step, and their fourth differences mostly that
// scatter: a bound at the anchors' 5e-4 px would refuse most lenses on it alone.
const double kCorrectionPx = 2e-3;
const double kCorrectionFraction = 2e-4;

// One error parameter of a lens, and the step of its differences.
struct ErrorParameter {
    // 0: dz (mm); 1: focal factor - 1; 2, 3: the axis's x, y; 4 + 2 a + c: the displacement of the
    // lens's adjacent lens a (adjacent_lenses' order: the same lattice direction for every lens)
    // from its own, component c (x, y; mm, array frame).
    int kind;
    double step;
};

// The parameters' largest count: four of the lens's own, two for each of up to eight adjacent lenses.
const int kMaxErrorParameters = 4 + 2 * 8;

// The lens's own error with parameter `kind` (< 4) at `value` and no other.
LensError error_with(int kind, double value)
{
    LensError e;
    if (kind == 0) {
        e.dz_mm = value;
    } else if (kind == 1) {
        e.focal_factor = 1 + value;
    } else {
        e.tilt_deg = std::asin(std::fabs(value)) * 180 / kPi;
        e.tilt_azimuth_deg = (kind == 2 ? 0 : 90) + (value < 0 ? 180 : 0);
    }
    return e;
}

// The lens's parameters' values, in `parameters`' order.
void error_values(const MicrolensArray& a, LensIndex lens, const std::vector<ErrorParameter>& parameters, double* x)
{
    const LensError e = a.error_of(lens);
    LensIndex adjacent[8];
    const int count = adjacent_lenses(a.grid, lens, adjacent);
    for (std::size_t p = 0; p < parameters.size(); ++p) {
        const int kind = parameters[p].kind;
        if (kind == 0) {
            x[p] = e.dz_mm;
        } else if (kind == 1) {
            x[p] = e.focal_factor - 1;
        } else if (kind < 4) {
            x[p] = kind == 2 ? e.axis.x : e.axis.y;
        } else {
            const int j = (kind - 4) / 2;
            const LensError n = j < count ? a.error_of(adjacent[j]) : e;
            x[p] = (kind - 4) % 2 == 0 ? n.dx_mm - e.dx_mm : n.dy_mm - e.dy_mm;
        }
    }
}

// The linear part of an affine map of sensor points (pixels): a vector's image.
template <class F> Vec2 linear_part(const F& map, Vec2 d)
{
    const Vec2 o = map(Vec2{0, 0}), p = map(d);
    return Vec2{p.x - o.x, p.y - o.y};
}

// Corrects the lenses of `out` interpolated from the ideal anchors (interpolated[i]) for their
// errors, as above; the lenses it cannot vouch for go onto `pending` (to be measured). `light`: the
// camera with errors whose light is measured. False when cancelled.
bool correct_for_errors(const PlenopticCamera& light, const Canonical& canonical, const Symmetry& symmetry,
                        const MicroimageOptions& options,
                        const std::vector<Vec2>& at, const std::vector<char>& interpolated, const double range[4], const MicroimageCancel& cancelled, std::vector<MicroimageTruth>& out,
                        std::vector<std::size_t>& pending, MicroimageWork& counts)
{
    const PlenopticCamera& am = canonical.model();
    const LensErrors& errors = *light.array.errors;
    std::vector<ErrorParameter> parameters;
    if (errors.max_dz_mm() > 0)
        parameters.push_back(ErrorParameter{0, errors.max_dz_mm()});
    if (errors.max_focal_deviation() > 0)
        parameters.push_back(ErrorParameter{1, errors.max_focal_deviation()});
    if (errors.tilts()) {
        const double h = std::sin(errors.max_tilt_deg() * kPi / 180);
        parameters.push_back(ErrorParameter{2, h});
        parameters.push_back(ErrorParameter{3, h});
    }
    if (errors.max_shift_mm() > 0) {
        LensIndex adjacent[8];
        const int count = adjacent_lenses(am.array.grid, LensIndex{0, 0}, adjacent);
        for (int c = 0; c < 2 * count; ++c)
            parameters.push_back(ErrorParameter{4 + c, errors.max_shift_mm() / std::sqrt(2.0)});
    }
    const std::size_t P = parameters.size();
    std::vector<std::size_t> lenses;  // the interpolated lenses
    for (std::size_t i = 0; i < out.size(); ++i)
        if (interpolated[i])
            lenses.push_back(i);
    if (P == 0 || lenses.empty())
        return true;

    // The Jacobian anchors: error_anchor_step lenses apart (at least five a side, else every lens is
    // measured).
    Anchors jacobian;
    jacobian.cover(options.error_anchor_step, range);
    std::vector<MicroimageTruth> anchors;
    if (jacobian.enough())
        anchors = jacobian.read_by(lenses, at, [](std::uint64_t) { return false; });
    if (anchors.empty()) {
        pending.insert(pending.end(), lenses.begin(), lenses.end());
        std::sort(pending.begin(), pending.end());
        return true;
    }
    // Where the camera's mirror symmetry holds (Symmetry), only the anchors' quarter lenses are
    // measured: a lens's microimage is its quarter lens's mirrored, with each parameter mirrored too
    // (the axis's and the displacements' components along a mirror change sign, an adjacent lens is
    // its mirror image's).
    struct Mirrored {
        std::size_t quarter;  // into `quarters`
        bool mirror_x, mirror_y;
    };
    std::vector<Mirrored> mirrored(anchors.size());
    std::vector<MicroimageTruth> quarters;
    {
        std::unordered_map<std::uint64_t, std::size_t> where;
        std::vector<LensIndex> of(anchors.size());
        for (std::size_t i = 0; i < anchors.size(); ++i) {
            Mirrored& mm = mirrored[i];
            mm.mirror_x = mm.mirror_y = false;
            of[i] = symmetry.valid() ? Symmetry::quarter_lens(am.array, anchors[i].lens, &mm.mirror_x, &mm.mirror_y)
                                     : anchors[i].lens;
            if (where.emplace(anchor_key(of[i]), 0).second) {
                MicroimageTruth t = MicroimageTruth();
                t.lens = of[i];
                quarters.push_back(t);
            }
        }
        for (std::size_t n = 0; n < quarters.size(); ++n)
            where[anchor_key(quarters[n].lens)] = n;
        for (std::size_t i = 0; i < anchors.size(); ++i)
            mirrored[i].quarter = where.at(anchor_key(of[i]));
    }
    // The perturbations measured: parameter `kind` at `value`, the lens's focal factor less 1 at
    // `focal` (besides that parameter's own). Each is a camera whose table perturbs every quarter
    // lens alike, each lens alone in its neighbourhood (the anchors lie far apart).
    struct Perturbation {
        int kind;
        double value, focal;
    };
    std::vector<Perturbation> perturbations;
    std::size_t focal = P;  // the focal factor's parameter (P: none)
    for (std::size_t p = 0; p < P; ++p)
        if (parameters[p].kind == 1)
            focal = p;
    // Where each parameter's measurements are among the perturbations: side[p][s] at +h (s = 0) and
    // -h, mixed[p][s] at +h with the focal factor's +step (s = 0) and -step.
    std::vector<std::array<std::size_t, 2>> side(P), mixed(P);
    for (std::size_t p = 0; p < P; ++p)
        for (int s = 0; s < 2; ++s) {
            const double sign = s == 0 ? 1 : -1;
            side[p][s] = perturbations.size();
            perturbations.push_back(Perturbation{parameters[p].kind, sign * parameters[p].step, 0});
            if (focal < P && p != focal) {
                mixed[p][s] = perturbations.size();
                perturbations.push_back(Perturbation{parameters[p].kind, parameters[p].step, sign * parameters[focal].step});
            }
        }
    const double type_focal = am.array.microlens->focal_length_mm(0);
    std::vector<PlenopticCamera> perturbed_model(perturbations.size(), am), perturbed_light(perturbations.size(),
                                                                                           canonical.light());
    for (std::size_t n = 0; n < perturbations.size(); ++n) {
        const Perturbation& pert = perturbations[n];
        std::vector<LensTableRow> rows;
        for (std::size_t i = 0; i < quarters.size(); ++i) {
            LensTableRow own;
            own.lens = quarters[i].lens;
            own.error = pert.kind < 4 ? error_with(pert.kind, pert.value) : LensError();
            if (pert.focal != 0)
                own.error.focal_factor = 1 + pert.focal;
            if (pert.kind < 4 || pert.focal != 0)
                rows.push_back(own);
            if (pert.kind >= 4) {
                LensIndex adjacent[8];
                adjacent_lenses(am.array.grid, quarters[i].lens, adjacent);
                LensTableRow next;
                next.lens = adjacent[(pert.kind - 4) / 2];
                ((pert.kind - 4) % 2 == 0 ? next.error.dx_mm : next.error.dy_mm) = pert.value;
                rows.push_back(next);
            }
        }
        const std::shared_ptr<const LensErrors> table = LensErrors::tabled(rows, std::string(), &type_focal, 1);
        perturbed_model[n].array.errors = table;
        perturbed_light[n].array.errors = table;
    }
    // Each quarter lens measured ideal from scratch, then with each perturbation, each region's
    // radii sought near the ideal lens's (a perturbation moves a boundary by a few hundredths of a
    // pixel where it acts, and most not at all). The answer is the grid step that holds the crossing,
    // as from scratch (boundary_on_grid); only the search is shorter (behind the 22 mm wide-angle
    // some 60 % of the probes from scratch; the coarse search about dark start points, a third of
    // those, is as long). On every thread, a quarter lens at a time; each result depends on the lens
    // alone.
    const LensMeasurer ideal_measurer(am, canonical.light(), options);
    std::vector<LensMeasurer> measurers;
    measurers.reserve(perturbations.size());
    for (std::size_t n = 0; n < perturbations.size(); ++n)
        measurers.emplace_back(perturbed_model[n], perturbed_light[n], options);
    std::vector<MicroimageTruth> ideal = quarters;
    std::vector<std::vector<MicroimageTruth>> measured(perturbations.size(), quarters);
    {
        std::atomic<std::size_t> next(0);
        std::atomic<bool> stop(false);
        auto work = [&](bool polls) {
            std::vector<CellNode> own_nodes;
            for (std::size_t i = next++; i < quarters.size() && !stop; i = next++) {
                LensMeasurer::Radii radii = ideal_measurer.fresh();
                ideal_measurer.measure(ideal[i], &radii, &own_nodes, nullptr);
                const std::vector<std::vector<std::vector<double>>> seed = radii.history;
                for (std::size_t n = 0; n < perturbations.size() && !stop; ++n) {
                    if (polls && cancelled && cancelled()) {
                        stop = true;
                        break;
                    }
                    radii.history = seed;
                    measurers[n].measure(measured[n][i], &radii, &own_nodes, nullptr);
                }
            }
        };
        const unsigned hardware = std::thread::hardware_concurrency();
        const int threads = options.threads > 0 ? options.threads : int(std::max(1u, hardware));
        std::vector<std::thread> workers;
        for (int t = 1; t < threads && std::size_t(t) < quarters.size(); ++t)
            workers.push_back(std::thread(work, false));
        work(true);
        for (std::thread& worker : workers)
            worker.join();
        if (stop)
            return false;
    }
    // Per quarter lens, for each parameter and each of du, dv and the lit fraction: J, H, and K (the
    // mixed difference with the focal factor: a lens's light near its cell's edge, where its
    // neighbours act, moves with its own focal length, some 9 % of the neighbours' effect a per cent
    // of focal length behind the 22 mm wide-angle).
    std::vector<char> valid(quarters.size(), 1);
    std::vector<std::vector<double>> jh(quarters.size(), std::vector<double>(9 * P, 0.0));
    auto value = [&](const MicroimageTruth& t, const MicroimageCentre& c, int q) {
        return q == 0 ? t.u_px - c.u : q == 1 ? t.v_px - c.v : t.lit_fraction;
    };
    const std::vector<MicroimageTruth>* focal_side[2] = {nullptr, nullptr};
    if (focal < P)
        for (int s = 0; s < 2; ++s)
            focal_side[s] = &measured[side[focal][s]];
    for (std::size_t p = 0; p < P; ++p) {
        const double h = parameters[p].step;
        const std::vector<MicroimageTruth>* up = &measured[side[p][0]];
        const std::vector<MicroimageTruth>* down = &measured[side[p][1]];
        const bool mixes = focal < P && p != focal;
        for (std::size_t i = 0; i < quarters.size(); ++i) {
            const MicroimageCentre c = microimage_centre_px(am, quarters[i].lens);
            bool lit = c.valid && (*up)[i].lit && ideal[i].lit && (*down)[i].lit;
            for (int s = 0; s < 2 && mixes; ++s)
                lit = lit && measured[mixed[p][s]][i].lit && (*focal_side[s])[i].lit;
            if (!lit) {
                valid[i] = 0;
                continue;
            }
            for (int q = 0; q < 3; ++q) {
                const double u = value((*up)[i], c, q), mid = value(ideal[i], c, q), d = value((*down)[i], c, q);
                jh[i][9 * p + q] = (u - d) / (2 * h);
                jh[i][9 * p + 3 + q] = (u - 2 * mid + d) / (h * h);
                if (mixes)
                    jh[i][9 * p + 6 + q] =
                        (value(measured[mixed[p][0]][i], c, q) - value(measured[mixed[p][1]][i], c, q) -
                         value((*focal_side[0])[i], c, q) + value((*focal_side[1])[i], c, q)) /
                        (2 * parameters[focal].step * h);
            }
        }
    }
    // Each anchor's from its quarter lens's.
    std::unordered_map<std::uint64_t, std::vector<double>> differences;
    for (std::size_t i = 0; i < anchors.size(); ++i) {
        const Mirrored& mm = mirrored[i];
        if (!valid[mm.quarter])
            continue;
        const std::vector<double>& from = jh[mm.quarter];
        if (!mm.mirror_x && !mm.mirror_y) {
            differences[anchor_key(anchors[i].lens)] = from;
            continue;
        }
        // The anchor's adjacent lens a is the mirror image of the quarter lens's adjacent[image[a]].
        const LensIndex lens = anchors[i].lens, quarter = quarters[mm.quarter].lens;
        LensIndex adjacent[8], quarter_adjacent[8];
        const int count = adjacent_lenses(am.array.grid, lens, adjacent);
        adjacent_lenses(am.array.grid, quarter, quarter_adjacent);
        int image[8];
        bool matched = true;
        for (int a = 0; a < count; ++a) {
            const Vec2 o = am.array.lattice_centre_local(adjacent[a]) - am.array.lattice_centre_local(lens);
            const Vec2 want{mm.mirror_x ? -o.x : o.x, mm.mirror_y ? -o.y : o.y};
            image[a] = -1;
            for (int b = 0; b < count; ++b) {
                const Vec2 ob =
                    am.array.lattice_centre_local(quarter_adjacent[b]) - am.array.lattice_centre_local(quarter);
                if (std::fabs(ob.x - want.x) + std::fabs(ob.y - want.y) < 1e-6 * am.array.pitch_mm)
                    image[a] = b;
            }
            matched = matched && image[a] >= 0;
        }
        if (!matched)
            continue;
        std::vector<double> to(9 * P, 0.0);
        for (std::size_t p = 0; p < P; ++p) {
            const int kind = parameters[p].kind;
            int source_kind = kind;
            double sign = 1;
            if (kind == 2 && mm.mirror_x)
                sign = -1;
            if (kind == 3 && mm.mirror_y)
                sign = -1;
            if (kind >= 4) {
                const int a = (kind - 4) / 2, c = (kind - 4) % 2;
                source_kind = 4 + 2 * image[a] + c;
                if ((c == 0 && mm.mirror_x) || (c == 1 && mm.mirror_y))
                    sign = -1;
            }
            std::size_t source = P;
            for (std::size_t r = 0; r < P; ++r)
                if (parameters[r].kind == source_kind)
                    source = r;
            for (int order = 0; order < 3; ++order) {  // J, H, K: J and K change sign with the parameter
                const double* f = &from[9 * source + 3 * order];
                double* t = &to[9 * p + 3 * order];
                const double factor = order == 1 ? 1 : sign;
                const Vec2 d = linear_part(
                    [&](Vec2 px) { return symmetry.map_px(am.sensor, mm.mirror_x, mm.mirror_y, px); },
                    Vec2{factor * f[0], factor * f[1]});
                t[0] = d.x;
                t[1] = d.y;
                t[2] = factor * f[2];
            }
        }
        differences[anchor_key(lens)].swap(to);
    }
    counts.error_anchors = quarters.size();

    // Each lens corrected, on every thread (each result depends on the lens alone).
    std::vector<char> measure(out.size(), 0);
    std::atomic<std::size_t> next(0);
    const std::size_t kChunk = 256;
    auto work = [&]() {
        for (std::size_t first = next.fetch_add(kChunk); first < lenses.size(); first = next.fetch_add(kChunk))
            for (std::size_t n = first; n < std::min(lenses.size(), first + kChunk); ++n) {
                const std::size_t index = lenses[n];
                MicroimageTruth& truth = out[index];
                std::int64_t i0, j0;
                double x, y;
                jacobian.stencil(at[index], &i0, &j0, &x, &y);
                const std::vector<double>* block[6][6] = {};
                bool missing = false;
                jacobian.each(i0, j0, [&](std::int64_t i, std::int64_t j) {
                    const auto found = differences.find(anchor_key(jacobian.lens(i, j)));
                    if (found == differences.end())
                        missing = true;
                    else
                        block[j - j0 + 1][i - i0 + 1] = &found->second;
                });
                if (missing) {
                    measure[index] = 1;
                    continue;
                }
                double xs[kMaxErrorParameters];
                error_values(light.array, truth.lens, parameters, xs);
                auto v = [&](std::int64_t i, std::int64_t j, int q) {
                    const std::vector<double>& d = *block[j - j0 + 1][i - i0 + 1];
                    double sum = 0;
                    const double xf = focal < P ? xs[focal] : 0;
                    for (std::size_t p = 0; p < P; ++p)
                        sum += d[9 * p + q] * xs[p] + 0.5 * d[9 * p + 3 + q] * xs[p] * xs[p] +
                               d[9 * p + 6 + q] * xs[p] * xf;
                    return sum;
                };
                const double allowed[3] = {kCorrectionPx, kCorrectionPx, kCorrectionFraction};
                double result[3];
                bool vouched = true;
                for (int q = 0; q < 3 && vouched; ++q) {
                    double error;
                    result[q] = cubic_through(jacobian, i0, j0, x, y, v, q, &error);
                    vouched = error <= allowed[q];
                }
                if (!vouched) {
                    measure[index] = 1;
                    continue;
                }
                const Vec2 d =
                    linear_part([&](Vec2 px) { return canonical.to_camera_px(px); }, Vec2{result[0], result[1]});
                truth.u_px += d.x;
                truth.v_px += d.y;
                truth.lit_fraction += result[2];
            }
    };
    const unsigned hardware = std::thread::hardware_concurrency();
    const int threads = options.threads > 0 ? options.threads : int(std::max(1u, hardware));
    std::vector<std::thread> workers;
    for (int t = 1; t < threads; ++t)
        workers.push_back(std::thread(work));
    work();
    for (std::thread& worker : workers)
        worker.join();
    std::size_t corrected = 0;
    for (std::size_t index : lenses) {
        if (measure[index])
            pending.push_back(index);
        else
            ++corrected;
    }
    std::sort(pending.begin(), pending.end());
    counts.corrected = corrected;
    return true;
}

} // namespace

std::vector<MicroimageTruth> microimage_truth(const PlenopticCamera& m, const MicroimageOptions& options,
                                              const MicroimageProgress& progress, const MicroimageCancel& cancelled,
                                              const PlenopticCamera* through, MicroimageWork* work)
{
    MicroimageWork unused;
    MicroimageWork& counts = work ? *work : unused;
    counts = MicroimageWork();
    // The lenses and their start points are this camera's; their light is traced through `through`.
    const PlenopticCamera& light = through ? *through : m;
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    std::vector<MicroimageTruth> out;
    if (m.array.grid == GridType::None || !m.lens || W <= 0 || H <= 0)
        return out;
    double box[4];
    if (!picture_on_array(m, box))
        return out;
    const double p = m.array.pitch_mm, rows = row_spacing(m.array.grid, p);
    // Margins of lenses: a lattice centre in the picture may belong to a lens whose centre
    // projects just outside the box of the corners (the centres project from the exit pupil).
    const double l0 = std::floor(box[1] / rows) - 2, l1 = std::ceil(box[3] / rows) + 2;
    const double k0 = std::floor(box[0] / p) - 3, k1 = std::ceil(box[2] / p) + 3;
    if (!(l1 - l0 < 1e7 && k1 - k0 < 1e7))
        return out;
    // The lenses whose lattice centre is in the picture: counted first, so that the list takes no
    // more memory than it holds (a Lytro-class raw has some 234,000).
    auto in_picture = [&](LensIndex lens, Vec2* centre_px) {
        const MicroimageCentre centre = microimage_centre_px(m, lens);
        *centre_px = Vec2{centre.u, centre.v};
        return centre.valid && centre.u >= -0.5 && centre.u < W - 0.5 && centre.v >= -0.5 && centre.v < H - 0.5;
    };
    for (int pass = 0; pass < 2; ++pass) {
        std::size_t count = 0;
        for (std::int64_t l = std::int64_t(l0); l <= std::int64_t(l1); ++l) {
            for (std::int64_t k = std::int64_t(k0); k <= std::int64_t(k1); ++k) {
                const LensIndex lens{k, l};
                Vec2 centre;
                if (!in_picture(lens, &centre))
                    continue;  // the lattice centre is not in the picture
                ++count;
                if (pass == 1) {
                    MicroimageTruth truth = MicroimageTruth();
                    truth.lens = lens;
                    out.push_back(truth);
                }
            }
        }
        if (pass == 0)
            out.reserve(count);
    }

    // Lenses measured so far (as the quarter lenses of the camera's symmetry).
    std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>> known;
    const Symmetry symmetry(m, light, options);
    // Refracting microlenses with manufacturing errors: the anchors are the ideal array's, and each
    // lens is interpolated where it sits, then corrected for its errors (correct_for_errors).
    PlenopticCamera ideal, ideal_light;
    const bool perturbed = options.error_anchor_step >= 4 && options.anchor_step >= 4 && m.array.errors &&
                           light.array.errors && m.array.microlens && refracting_shape(*m.array.microlens) != nullptr;
    if (perturbed) {
        ideal = m;
        ideal.array.errors = nullptr;
        ideal_light = light;
        ideal_light.array.errors = nullptr;
    }
    const PlenopticCamera& base = perturbed ? ideal : m;
    const PlenopticCamera& base_light = perturbed ? ideal_light : light;
    if (!interpolates(base, base_light, options) || out.empty()) {
        counts.measured = out.size();
        if (!measure_symmetric(m, light, options, out, 1, progress, cancelled, nullptr, &known))
            out.clear();
        counts.quarter_lenses = symmetry.valid() ? known.size() : 0;
        return out;
    }
    // Levels of anchors: anchor_step, then half of it, ... down to 4 lenses apart. At each level the
    // lenses not yet interpolated get the anchors they read (those not measured yet are measured),
    // and are interpolated where those vouch for the cubic; the rest go on to the next level (near
    // where the main lens begins to vignette, the light changes too fast for the coarser anchors).
    // The lenses left at the end are measured. Every decision depends on the lenses alone. The
    // anchors are measured in canonical.model() (the camera itself, or its array turned back onto
    // the axis: Canonical), the lenses left in the camera.
    const Canonical canonical(base, base_light, options);
    const PlenopticCamera& am = canonical.model();
    const Symmetry anchor_symmetry(am, canonical.light(), options);
    // A lens's displacement in the array's plane (perturbed: where the ideal lens it is sits).
    auto shift = [&](LensIndex lens) {
        if (!perturbed)
            return Vec2{0, 0};
        const LensError e = m.array.error_of(lens);
        return Vec2{e.dx_mm, e.dy_mm};
    };
    // Where each lens lies among the anchors; their range (X from range[0] to range[1], Y from
    // range[2] to range[3]).
    std::vector<Vec2> at(out.size());
    double range[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
    for (std::size_t i = 0; i < out.size(); ++i) {
        at[i] = canonical.position(out[i].lens, shift(out[i].lens));
        range[0] = std::min(range[0], at[i].x);
        range[1] = std::max(range[1], at[i].x);
        range[2] = std::min(range[2], at[i].y);
        range[3] = std::max(range[3], at[i].y);
    }
    // Quarter lenses measured as anchors in the canonical camera (`known` holds the camera's own).
    std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>> known_canonical;
    auto& anchor_known = canonical.active() ? known_canonical : known;
    const std::size_t total = out.size();
    std::unordered_map<std::uint64_t, AnchorValue> values;
    std::vector<std::size_t> pending(out.size());  // indices into `out` not yet found
    for (std::size_t i = 0; i < out.size(); ++i)
        pending[i] = i;
    // Progress: the anchors are the first half of the work, the lenses measured after them the rest.
    auto share = [&](std::size_t first) {
        return progress ? MicroimageProgress([&progress, first, total](std::size_t now, std::size_t count) {
            progress(first + now * (total / 4) / std::max<std::size_t>(1, count), total);
        })
                        : MicroimageProgress();
    };
    // Perturbed: whether each lens was interpolated between the anchors.
    std::vector<char> interpolated(perturbed ? out.size() : 0, 0);
    int level = 0;
    for (std::int64_t step = options.anchor_step; step >= 4 && !pending.empty(); step /= 2, ++level) {
        if (step % 2 != 0)
            break;
        Anchors anchors;
        anchors.values = &values;
        anchors.cover(step, range);
        if (!anchors.enough())
            break;  // fewer than five anchors a side
        // The anchors the pending lenses read that are not measured yet (sorted row by row below).
        std::vector<MicroimageTruth> measured =
            anchors.read_by(pending, at, [&](std::uint64_t key) { return values.count(key) != 0; });
        // Anchors that cost more than measuring the lenses they serve: measure those lenses. (What
        // a set of lenses costs: the lenses to measure for it, the quarter lenses with the symmetry.)
        auto cost = [&](const Symmetry& sym, const MicrolensArray& array,
                        const std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>>& done,
                        std::size_t count, const std::function<LensIndex(std::size_t)>& lens_at) {
            if (!sym.valid())
                return count;
            std::unordered_map<std::uint64_t, char> seen;
            for (std::size_t i = 0; i < count; ++i) {
                bool mirror_x, mirror_y;
                const std::uint64_t key = anchor_key(Symmetry::quarter_lens(array, lens_at(i), &mirror_x, &mirror_y));
                if (done.count(key) == 0)
                    seen.emplace(key, 1);
            }
            return seen.size();
        };
        if (4 * cost(anchor_symmetry, am.array, anchor_known, measured.size(),
                     [&](std::size_t i) { return measured[i].lens; }) >
            cost(symmetry, m.array, known, pending.size(), [&](std::size_t i) { return out[pending[i]].lens; }))
            break;
        sort_row_by_row(measured);
        std::vector<char> lobes;
        if (!measure_symmetric(am, canonical.light(), options, measured, step, share(std::min(level, 1) * total / 4),
                               cancelled, &lobes, &anchor_known)) {
            out.clear();
            return out;
        }
        counts.anchors += measured.size();
        for (std::size_t n = 0; n < measured.size(); ++n) {
            const MicroimageTruth& t = measured[n];
            const MicroimageCentre centre = microimage_centre_px(am, t.lens);
            AnchorValue value;
            value.lobe = lobes[n] != 0;
            value.lit = t.lit && centre.valid;
            value.value[0] = value.lit ? t.u_px - centre.u : 0;
            value.value[1] = value.lit ? t.v_px - centre.v : 0;
            value.value[2] = t.lit_fraction;
            values[anchor_key(t.lens)] = value;
        }
        // The lenses left, kept in place (the list is 8 bytes a lens of the picture at first).
        std::size_t left = 0;
        for (std::size_t index : pending) {
            Vec2 centre;
            if (!canonical.centre_px(out[index].lens, &centre, shift(out[index].lens)) ||
                !interpolate(anchors, at[index], &out[index], centre)) {
                pending[left++] = index;
                continue;
            }
            if (perturbed)
                interpolated[index] = 1;
            const Vec2 c = canonical.to_camera_px(Vec2{out[index].u_px, out[index].v_px});
            out[index].u_px = c.x;
            out[index].v_px = c.y;
        }
        pending.resize(left);
        pending.shrink_to_fit();
    }
    if (perturbed && counts.anchors > 0) {
        if (!correct_for_errors(light, canonical, anchor_symmetry, options, at, interpolated, range,
                                cancelled, out, pending, counts)) {
            out.clear();
            return out;
        }
    }
    counts.interpolated = out.size() - pending.size();
    counts.measured = pending.size();
    if (counts.anchors == 0) {
        // No level paid: every lens measured.
        if (!measure_symmetric(m, light, options, out, 1, progress, cancelled, nullptr, &known))
            out.clear();
        counts.quarter_lenses = symmetry.valid() ? known.size() : 0;
        return out;
    }
    std::vector<MicroimageTruth> measured(pending.size(), MicroimageTruth());
    for (std::size_t i = 0; i < pending.size(); ++i)
        measured[i].lens = out[pending[i]].lens;
    if (!measure_symmetric(m, light, options, measured, 1, share(total / 2), cancelled, nullptr, &known)) {
        out.clear();
        return out;
    }
    for (std::size_t i = 0; i < pending.size(); ++i)
        out[pending[i]] = measured[i];
    // (With errors the anchors' quarter lenses are the ideal array's, and the lenses left are measured
    // each where they are.)
    counts.quarter_lenses = canonical.active() || (perturbed && anchor_symmetry.valid())
                                ? anchor_known.size() + pending.size()
                                : (symmetry.valid() ? known.size() : 0);
    return out;
}

std::vector<MicroimageTruth> measured_microimages(const PlenopticCamera& m, const std::vector<LensIndex>& lenses,
                                                  const MicroimageOptions& options, const PlenopticCamera* through)
{
    std::vector<MicroimageTruth> out(lenses.size(), MicroimageTruth());
    for (std::size_t i = 0; i < lenses.size(); ++i)
        out[i].lens = lenses[i];
    if (m.array.grid == GridType::None || !m.lens)
        return std::vector<MicroimageTruth>();
    measure_symmetric(m, through ? *through : m, options, out, 1, MicroimageProgress(), MicroimageCancel(), nullptr,
                      nullptr);
    return out;
}

LatticeFit fit_microimage_lattice(const PlenopticCamera& m, const std::vector<MicroimageTruth>& truth)
{
    LatticeFit fit = LatticeFit();
    fit.valid = false;
    // Least squares on centred indices (k_s - mk, l - ml): the normal equations separate the mean.
    double mk = 0, ml = 0, mu = 0, mv = 0;
    std::size_t n = 0;
    for (const MicroimageTruth& t : truth) {
        if (!t.lit)
            continue;
        mk += double(skew_k(m.array.grid, t.lens));
        ml += double(t.lens.l);
        mu += t.u_px;
        mv += t.v_px;
        ++n;
    }
    if (n < 3)
        return fit;
    mk /= n;
    ml /= n;
    mu /= n;
    mv /= n;
    double skk = 0, skl = 0, sll = 0, sku = 0, slu = 0, skv = 0, slv = 0;
    for (const MicroimageTruth& t : truth) {
        if (!t.lit)
            continue;
        const double dk = double(skew_k(m.array.grid, t.lens)) - mk, dl = double(t.lens.l) - ml;
        skk += dk * dk;
        skl += dk * dl;
        sll += dl * dl;
        sku += dk * (t.u_px - mu);
        slu += dl * (t.u_px - mu);
        skv += dk * (t.v_px - mv);
        slv += dl * (t.v_px - mv);
    }
    const double det = skk * sll - skl * skl;
    if (!(det > 1e-9 * std::max(1.0, skk * sll)))
        return fit;  // all lit lenses in one row or one column
    fit.basis_a_px[0] = (sku * sll - slu * skl) / det;
    fit.basis_b_px[0] = (slu * skk - sku * skl) / det;
    fit.basis_a_px[1] = (skv * sll - slv * skl) / det;
    fit.basis_b_px[1] = (slv * skk - skv * skl) / det;
    fit.origin_px[0] = mu - fit.basis_a_px[0] * mk - fit.basis_b_px[0] * ml;
    fit.origin_px[1] = mv - fit.basis_a_px[1] * mk - fit.basis_b_px[1] * ml;
    fit.valid = true;
    fit.lenses = n;
    double sum2 = 0;
    for (const MicroimageTruth& t : truth) {
        if (!t.lit)
            continue;
        const double r = length(lattice_residual(m, fit, t));
        sum2 += r * r;
        if (r >= fit.max_residual_px) {
            fit.max_residual_px = r;
            fit.worst = t.lens;
        }
    }
    fit.rms_residual_px = std::sqrt(sum2 / n);
    return fit;
}

Vec2 lattice_residual(const PlenopticCamera& m, const LatticeFit& fit, const MicroimageTruth& lens)
{
    const double k = double(skew_k(m.array.grid, lens.lens)), l = double(lens.lens.l);
    return Vec2{lens.u_px - (fit.origin_px[0] + k * fit.basis_a_px[0] + l * fit.basis_b_px[0]),
                lens.v_px - (fit.origin_px[1] + k * fit.basis_a_px[1] + l * fit.basis_b_px[1])};
}

MicroimageSummary summarise_microimages(const PlenopticCamera& m, const std::vector<MicroimageTruth>& truth,
                                        const MicroimageOptions& options, const std::string& file)
{
    MicroimageSummary summary;
    summary.file = file;
    summary.lenses = truth.size();
    summary.lit_lenses = 0;
    summary.options = options;
    summary.lens_errors = m.array.errors != nullptr;
    summary.fit = fit_microimage_lattice(m, truth);
    double sum2 = 0, largest = 0;
    for (const MicroimageTruth& t : truth) {
        if (!t.lit)
            continue;
        const MicroimageCentre centre = microimage_centre_px(m, t.lens);
        if (!centre.valid)
            continue;
        const double u = centre.u, v = centre.v;
        ++summary.lit_lenses;
        const double r = std::hypot(t.u_px - u, t.v_px - v);
        sum2 += r * r;
        largest = std::max(largest, r);
    }
    summary.from_lattice_rms_px = summary.lit_lenses > 0 ? std::sqrt(sum2 / summary.lit_lenses) : NAN;
    summary.from_lattice_max_px = summary.lit_lenses > 0 ? largest : NAN;
    return summary;
}

namespace {

// The shortest "%.*g" that reads back to the same double.
std::string shortest(double value)
{
    char buffer[40];
    for (int digits = 1; digits <= 17; ++digits) {
        std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
        if (std::strtod(buffer, nullptr) == value)
            break;
    }
    return buffer;
}

} // namespace

std::string microimages_csv_header(const PlenopticCamera& m, bool per_channel)
{
    std::string out = "k,l,u,v,lit_fraction,residual_u,residual_v";
    out += per_channel ? ",u_r,v_r,u_g,v_g,u_b,v_b" : "";
    out += m.array.errors ? ",dx_mm,dy_mm,dz_mm,focal_length_mm,tilt_deg,tilt_azimuth_deg\n" : "\n";
    return out;
}

std::string microimages_csv_lines(const PlenopticCamera& m, const std::vector<MicroimageTruth>& truth,
                                  const LatticeFit& fit, const std::vector<std::vector<MicroimageTruth>>& channels,
                                  std::size_t begin, std::size_t end)
{
    const bool per_channel = channels.size() == 3;
    const bool errors = m.array.errors != nullptr;
    std::string out;
    for (std::size_t index = begin; index < end && index < truth.size(); ++index) {
        const MicroimageTruth& t = truth[index];
        out += std::to_string(static_cast<long long>(t.lens.k)) + "," + std::to_string(static_cast<long long>(t.lens.l));
        if (t.lit) {
            out += "," + shortest(t.u_px) + "," + shortest(t.v_px) + "," + shortest(t.lit_fraction);
            if (fit.valid) {
                const Vec2 r = lattice_residual(m, fit, t);
                out += "," + shortest(r.x) + "," + shortest(r.y);
            } else {
                out += ",,";
            }
        } else {
            out += ",,," + shortest(t.lit_fraction) + ",,";
        }
        for (std::size_t c = 0; per_channel && c < 3; ++c) {
            const MicroimageTruth& ct = channels[c][index];
            out += ct.lit ? "," + shortest(ct.u_px) + "," + shortest(ct.v_px) : ",,";
        }
        if (errors) {
            // The lens as it is (array/lens_errors.h): the columns a lens_table reads back.
            const LensError e = m.array.error_of(t.lens);
            out += "," + shortest(e.dx_mm) + "," + shortest(e.dy_mm) + "," + shortest(e.dz_mm) + ",";
            out += m.array.microlens->forms_image() ? shortest(m.array.focal_length_mm(t.lens)) : std::string();
            out += "," + shortest(e.tilt_deg) + "," + shortest(e.tilt_azimuth_deg);
        }
        out += "\n";
    }
    return out;
}

std::string microimages_csv(const PlenopticCamera& m, const std::vector<MicroimageTruth>& truth, const LatticeFit& fit,
                            const std::vector<std::vector<MicroimageTruth>>& channels)
{
    return microimages_csv_header(m, channels.size() == 3) +
           microimages_csv_lines(m, truth, fit, channels, 0, truth.size());
}

} // namespace plenoptic
