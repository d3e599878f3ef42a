// SPDX-License-Identifier: AGPL-3.0-or-later
// A lens's microimage measured through the renderer's rays (see the header).

#include "plenoptic/truth/microimage_measure.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/array/refracting_microlens.h"
#include "plenoptic/lens/pupil_bounds.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/camera/rays_internal.h"
#include "plenoptic/core/sampling.h"
#include "plenoptic/core/threads.h"

namespace plenoptic {
namespace microimage_detail {

using detail::project_to_array;

namespace {

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

LensMeasurer::LensMeasurer(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options)
    : m_(m), light_(light), options_(options), all_nodes_(cell_nodes(m, options)),
      // Refracting lenses that may be displaced: each lens's cell points moved into its own cell.
      cut_cells_(light.array.errors && light.array.errors->max_shift_mm() > 0 &&
                 refracting_shape(*light.array.microlens) != nullptr)
{
}

void LensMeasurer::measure(MicroimageTruth& truth, Radii* radii, std::vector<CellNode>* own_nodes, bool* lobe_out) const
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

bool measure_lenses(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options,
                    std::vector<MicroimageTruth>& out, std::int64_t step, const MicroimageProgress& progress,
                    const MicroimageCancel& cancelled, std::vector<char>* lobes)
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
    run_on_threads(thread_count(options.threads, runs.size() - 1), [&](int t) {
        const bool reports = t == 0;
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
    });
    return !stop;
}

void sort_row_by_row(std::vector<MicroimageTruth>& lenses)
{
    std::sort(lenses.begin(), lenses.end(), [](const MicroimageTruth& p, const MicroimageTruth& q) {
        return p.lens.l != q.lens.l ? p.lens.l < q.lens.l : p.lens.k < q.lens.k;
    });
}

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

} // namespace microimage_detail
} // namespace plenoptic
