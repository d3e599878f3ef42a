// SPDX-License-Identifier: AGPL-3.0-or-later
// Exit-pupil bounds of a real lens per field radius (see the header).
//
// For a field point P = (r, 0, plane_z) the rays that pass all pass the rear surface inside its
// clear aperture, so they cross the exit pupil's plane inside the shadow of that aperture cast from
// P: a square around it is searched on a grid. The passing grid points give a first centre and
// radius; the radius is then refined along kAzimuths directions from the centre by bisection on
// the boundary, which the grid knows only to a cell. The region is close to convex (an
// intersection of the apertures' images), so the largest boundary distance with a small margin
// holds it. Points between two bins use a disc holding both bins' discs.

#include "plenoptic/lens/pupil_bounds.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <exception>

#include "plenoptic/core/convex_hull.h"
#include "plenoptic/core/setup_progress.h"
#include "plenoptic/core/threads.h"

namespace plenoptic {

namespace {

const int kBins = 48;            // field radii sampled from the axis to the edge of the field
const int kGrid = 48;            // grid points a side over the search square
const int kAzimuths = 64;        // boundary directions refined by bisection
const int kBisections = 24;      // steps of each bisection (2^-24 of the grid radius)
const double kMargin = 1.01;     // radius margin for the bins, and again for points between them
const int kMaxFieldDoublings = 60;
// Tight discs (for aiming): boundary directions, tight spans per bin (the passing region changes
// shape quickly where vignetting sets in: the double Gauss's and the fisheye's off-axis regions
// needed spans a quarter of the bins' to be held closely; the radii measured are those the spans
// of whole bins measured before, at each bin and three between), and the margin on each span's
// radius for what lies between the measured radii (validated by brute force in pupil_bounds_test).
const int kTightAzimuths = 512;
const int kTightScan = 16 * kGrid;  // points along the x axis where the grid's centre is dark
const int kTightSplit = 4;
const double kTightMargin = 1.0001;
// The cutting discs' further margin: their far side follows the region's edge across the field
// less smoothly than the disc does (the double Gauss's near the axis left 0.3 um between the
// measured radii with kTightMargin alone; validated by brute force in pupil_bounds_test).
const double kCutMargin = 1.0003;
// A lens with a conic or aspheric surface: its rear surface's sag is sampled at kAsphereSagSamples
// heights for the search square, and every disc's radius is widened by kAsphereMargin more (an
// asphere can make the passing region less convex than spheres do).
const int kAsphereSagSamples = 256;
const double kAsphereSagMargin = 1.05;
const double kAsphereMargin = 1.03;

struct Probe {
    const MainLens& lens;
    double plane_z, pupil_z;
    bool passes(double r, double x, double y) const
    {
        const Vec3 from{r, 0, plane_z};
        return lens.to_scene(from, Vec3{x, y, pupil_z} - from, true).passed;
    }
};

// The square of the exit pupil's plane (centre x, half-size) that the rear surface's clear aperture
// shadows from (r, 0, plane_z): the aperture's rim lies somewhere between the rear vertex's plane
// and its sag, so both planes' shadows are joined.
void search_square(const Prescription& lens, double r, double plane_z, double pupil_z, double* centre_x, double* half)
{
    const LensSurface& rear = lens.surfaces.back();
    const double a = 0.5 * rear.aperture_mm;
    double sag = 0;
    if (rear.is_aspheric() && !rear.stop) {
        // The largest |sag| within the aperture, sampled (check_prescription has made it defined
        // there), widened by kAsphereSagMargin for what lies between the samples.
        for (int k = 0; k <= kAsphereSagSamples; ++k)
            sag = std::max(sag, std::fabs(surface_sag_mm(rear, a * k / kAsphereSagSamples)));
        sag *= kAsphereSagMargin;
    } else if (rear.radius_mm != 0 && !rear.stop)
        sag = std::fabs(rear.radius_mm) - std::sqrt(std::max(0.0, rear.radius_mm * rear.radius_mm - a * a));
    double lo = INFINITY, hi = -INFINITY;
    for (double z_rim : {-sag, sag}) {
        const double t = (pupil_z - plane_z) / (z_rim - plane_z);  // P + t (rim - P) reaches the pupil plane
        const double c = r + t * (0 - r);
        lo = std::min(lo, c - std::fabs(t) * a);
        hi = std::max(hi, c + std::fabs(t) * a);
    }
    *centre_x = 0.5 * (lo + hi);
    *half = 0.5 * (hi - lo);
}

// Replaces `points` by the corners of their convex hull (Andrew's monotone chain; points on its
// edges dropped).
void keep_convex_hull(std::vector<Vec2>* points)
{
    std::vector<Vec2>& p = *points;
    if (p.size() < 3)
        return;
    std::vector<Vec2> hull(2 * p.size());
    hull.resize(size_t(convex_hull(p.data(), int(p.size()), hull.data())));
    hull.shrink_to_fit();
    p.swap(hull);
}

// Whether any ray from field radius r passes, and then the bin's disc.
bool bin_disc(const Prescription& lens, const Probe& probe, double r, double* centre_x, double* radius,
              bool tight = false, std::vector<Vec2>* hull = nullptr)
{
    const int azimuths = tight ? kTightAzimuths : kAzimuths;
    double sx, half;
    search_square(lens, r, probe.plane_z, probe.pupil_z, &sx, &half);
    if (!(std::isfinite(sx) && std::isfinite(half) && half > 0))
        return false;
    const double cell = 2 * half / kGrid;
    double lo = INFINITY, hi = -INFINITY, y_hi = 0;
    std::vector<Vec2> passing;
    for (int j = 0; j < kGrid; ++j) {
        for (int i = 0; i < kGrid; ++i) {
            const double x = sx - half + (i + 0.5) * cell, y = -half + (j + 0.5) * cell;
            if (!probe.passes(r, x, y))
                continue;
            passing.push_back(Vec2{x, y});
            lo = std::min(lo, x);
            hi = std::max(hi, x);
            y_hi = std::max(y_hi, std::fabs(y));
        }
    }
    if (passing.empty())
        return false;
    const double cx = 0.5 * (lo + hi);
    double grid_radius = 0;
    for (const Vec2& p : passing)
        grid_radius = std::max(grid_radius, std::hypot(p.x - cx, p.y));
    grid_radius += 2 * cell;  // a passing point lies within a cell diagonal of a passing grid point
    // The farthest the region can reach from a point of the x axis: the search square's far corner.
    auto square_reach = [&](double x) { return std::hypot(std::fabs(x - sx) + half, half) * (1 + 1e-9); };
    // The boundary measured along `azimuths` directions from (x0, 0), by bisection: the radius of a
    // disc about it that holds the region (infinite when the region is not star-shaped about it),
    // and the x extent of the boundary points.
    auto refine = [&](double x0, double* x_lo, double* x_hi, std::vector<Vec2>* corners) {
        if (!probe.passes(r, x0, 0))
            return double(INFINITY);
        double reach = 0;
        *x_lo = INFINITY;
        *x_hi = -INFINITY;
        std::vector<Vec2> ends;  // tight: the bisections' outer ends, from (x0, 0)
        if (tight)
            ends.reserve(size_t(azimuths));
        for (int k = 0; k < azimuths; ++k) {
            const double angle = 2 * kPi * k / azimuths;
            const double dx = std::cos(angle), dy = std::sin(angle);
            // Tight: from beyond the search square's farthest corner, which holds the region (a
            // sliver of a region near the field's edge, narrower than the grid's cells, reaches
            // farther than the few grid points on it).
            double inside = 0, outside = tight ? square_reach(x0) : grid_radius + std::fabs(x0 - cx);
            for (int s = 0; s < kBisections; ++s) {
                const double mid = 0.5 * (inside + outside);
                if (probe.passes(r, x0 + mid * dx, mid * dy))
                    inside = mid;
                else
                    outside = mid;
            }
            reach = std::max(reach, outside);
            *x_lo = std::min(*x_lo, x0 + outside * dx);
            *x_hi = std::max(*x_hi, x0 + outside * dx);
            if (tight)
                ends.push_back(Vec2{outside * dx, outside * dy});
        }
        if (tight) {
            // A convex region's boundary between directions k and k + 1 lies in the triangle of the
            // chord from end k to end k + 1 and the lines through ends k - 1, k and k + 2, k + 1
            // (a boundary point beyond either line would put end k or k + 1 inside the region): so
            // the apex where those lines meet bounds it, also at a corner of the region (where the
            // boundary turns sharply between two directions). Where the lines do not meet beyond
            // the chord (the region is not convex there, or straight), the chord's ends over
            // cos(pi / n), as the bounds take it.
            const double slack = 1 / std::cos(kPi / azimuths);
            double bound = reach;
            // The polygon holding the region (for the cutting discs): (x0, 0), the ends, the apexes,
            // and where the directions' lines are not met, the ends taken out to the chord's bound
            // over cos(pi / n) (the sector there lies in that triangle); the grid's points too.
            if (corners) {
                corners->clear();
                corners->push_back(Vec2{x0, 0});
                for (const Vec2& p : passing)
                    corners->push_back(p);
            }
            for (int k = 0; k < azimuths; ++k) {
                const Vec2 p0 = ends[size_t((k + azimuths - 1) % azimuths)], p1 = ends[size_t(k)];
                const Vec2 q1 = ends[size_t((k + 1) % azimuths)], q0 = ends[size_t((k + 2) % azimuths)];
                const double d1x = p1.x - p0.x, d1y = p1.y - p0.y, d2x = q1.x - q0.x, d2y = q1.y - q0.y;
                const double den = d1x * d2y - d1y * d2x;
                const double wx = q1.x - p1.x, wy = q1.y - p1.y;
                const double sa = (wx * d2y - wy * d2x) / den, ta = (wx * d1y - wy * d1x) / den;
                const double chord = std::max(std::hypot(p1.x, p1.y), std::hypot(q1.x, q1.y));
                double apex = chord * slack;
                const bool met = std::isfinite(sa) && std::isfinite(ta) && sa >= 0 && ta >= 0;
                if (met)
                    apex = std::max(chord, std::hypot(p1.x + sa * d1x, p1.y + sa * d1y));
                bound = std::max(bound, apex);
                if (corners) {
                    const double grow = 1 + 1e-6;
                    if (met) {
                        corners->push_back(Vec2{x0 + p1.x * grow, p1.y * grow});
                        corners->push_back(Vec2{x0 + (p1.x + sa * d1x) * grow, (p1.y + sa * d1y) * grow});
                    } else {
                        const double out = chord * slack * slack * grow;
                        const double n1 = std::hypot(p1.x, p1.y), n2 = std::hypot(q1.x, q1.y);
                        if (n1 > 0)
                            corners->push_back(Vec2{x0 + p1.x / n1 * out, p1.y / n1 * out});
                        if (n2 > 0)
                            corners->push_back(Vec2{x0 + q1.x / n2 * out, q1.y / n2 * out});
                    }
                }
            }
            reach = bound * (1 + 1e-6);  // and the bisections' own resolution (2^-24)
        } else {
            // Between two of the directions a convex region's boundary reaches at most 1 / cos(pi / n)
            // times farther; and a region the bisection misread must still hold the grid's points.
            reach /= std::cos(kPi / azimuths);
        }
        for (const Vec2& p : passing)
            reach = std::max(reach, std::hypot(p.x - x0, p.y));
        return reach;
    };
    double x_lo = 0, x_hi = 0;
    std::vector<Vec2> corners;
    double x0 = cx;
    // Tight: a point of the region on the x axis to measure from. The grid's centre, or where a scan
    // along the axis finds light: near the field's edge the region is a sliver narrower than the
    // grid's cells, which the grid sees at a few points only (so its centre and its radius, which
    // the bounds keep, may miss the sliver's ends; the tight discs do not use them).
    bool start_found = tight && probe.passes(r, cx, 0);
    double start = cx;
    for (int k = 0; tight && !start_found && k < kTightScan; ++k) {
        start = sx - half + (k + 0.5) * 2 * half / kTightScan;
        start_found = probe.passes(r, start, 0);
    }
    if (start_found) {
        // The grid's centre is off by up to a grid cell (which made neighbouring radii's discs
        // jump): measured from the middle of the region's x extent instead, found by bisection
        // along the x axis (the region is symmetric about it, so a convex one is widest there).
        double ends[2];
        for (int side = 0; side < 2; ++side) {
            double inside = 0, outside = square_reach(start);
            for (int s = 0; s < kBisections; ++s) {
                const double mid = 0.5 * (inside + outside);
                if (probe.passes(r, start + (side ? mid : -mid), 0))
                    inside = mid;
                else
                    outside = mid;
            }
            ends[side] = start + (side ? outside : -outside);
        }
        x0 = 0.5 * (ends[0] + ends[1]);
    }
    double refined = refine(x0, &x_lo, &x_hi, tight ? &corners : nullptr);
    if (!std::isfinite(refined) && x0 != cx) {
        x0 = cx;
        refined = refine(x0, &x_lo, &x_hi, &corners);
    }
    bool measured = std::isfinite(refined);
    if (!measured)
        refined = tight ? square_reach(x0) : grid_radius;  // not star-shaped about its centre: what surely holds it
    *centre_x = x0;
    if (hull) {
        hull->clear();
        if (tight && measured) {
            // Only the corners' convex hull is kept: the farthest point of a set from a point (and
            // from a point or its mirror image, reach_from_pair: the larger of two convex functions)
            // is one of its hull's corners, so both reaches are unchanged, and the grid's inner
            // points no longer take memory or time in the cutting discs' search.
            hull->swap(corners);  // empty: no polygon (the region was not measured star-shaped)
            keep_convex_hull(hull);
        }
    }
    // Tight: the measured boundary (the bisection's outer ends, the convex allowance between the
    // directions, the grid's passing points); the bounds add kMargin and keep the grid's radius
    // where it is smaller.
    *radius = tight ? refined : std::min(grid_radius, refined * kMargin);
    return true;
}

// The smallest disc holding two discs centred on the x axis.
void enclose(double c1, double r1, double c2, double r2, double* c, double* r)
{
    const double lo = std::min(c1 - r1, c2 - r2), hi = std::max(c1 + r1, c2 + r2);
    *c = 0.5 * (lo + hi);
    *r = 0.5 * (hi - lo);
}

// The radius of the disc centred at (x, 0) holding the polygon `hull` (its farthest corner).
double reach_from(const std::vector<Vec2>& hull, double x)
{
    double reach2 = 0;  // squared (millimetres: neither overflows nor underflows)
    for (const Vec2& p : hull)
        reach2 = std::max(reach2, (p.x - x) * (p.x - x) + p.y * p.y);
    return std::sqrt(reach2) * (1 + 1e-15);
}

// The radius of the discs centred at (x, y) and (x, -y) that both hold `hull` (the farther of a
// point from either centre is |p.x - x| across and |p.y| + |y| along y).
double reach_from_pair(const std::vector<Vec2>& hull, double x, double y)
{
    double reach2 = 0;
    for (const Vec2& p : hull) {
        const double dy = std::fabs(p.y) + std::fabs(y);
        reach2 = std::max(reach2, (p.x - x) * (p.x - x) + dy * dy);
    }
    return std::sqrt(reach2) * (1 + 1e-15);
}

// The area of the intersection of `discs` (centre x, y and radius each), all holding (x0, 0): a
// sum over kAreaDirections directions from it.
struct Circle {
    double x, y, r;
};
const int kAreaDirections = 64;  // (the areas only rank the choices of cutting discs)
double area_of(double x0, const Circle* discs, int count)
{
    static const std::vector<Vec2> directions = [] {
        std::vector<Vec2> u;
        for (int k = 0; k < kAreaDirections; ++k) {
            const double a = 2 * kPi * (k + 0.5) / kAreaDirections;
            u.push_back(Vec2{std::cos(a), std::sin(a)});
        }
        return u;
    }();
    double area = 0;
    for (const Vec2& u : directions) {
        double t = INFINITY;
        for (int d = 0; d < count; ++d) {  // |(x0, 0) + t u - centre|^2 = r^2
            const double wx = x0 - discs[d].x, wy = -discs[d].y;
            const double b = wx * u.x + wy * u.y, q = wx * wx + wy * wy - discs[d].r * discs[d].r;
            t = std::min(t, -b + std::sqrt(std::max(0.0, b * b - q)));
        }
        area += 0.5 * t * t;
    }
    return area * 2 * kPi / kAreaDirections;
}

// The smallest disc holding two discs (centres a and b).
Circle enclose_circles(const Circle& a, const Circle& b)
{
    const double d = std::hypot(b.x - a.x, b.y - a.y);
    if (d + b.r <= a.r)
        return a;
    if (d + a.r <= b.r)
        return b;
    const double r = 0.5 * (d + a.r + b.r), t = (r - a.r) / d;
    return Circle{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), r};
}

// Offsets of the cutting discs' centres from the region's, in units of its disc's radius: kCutOffsets
// values in geometric steps from kCutOffsetLow to kCutOffsetHigh, refined about the best (a fixed
// list of ten missed the fisheye's best offsets by enough to cost 1.5 points of its edge's aimed
// samples).
const int kCutOffsets = 20;
const int kCutRefinements = 3;
// The pair of cutting discs off the axis: directions (kPairAngles - 1 between 0 and 180 degrees from
// +x), offsets (kPairOffsets in geometric steps, in units of the disc's radius), refined about the
// best kPairRefinements times, and the least share of the area it must take off to be kept.
const int kPairAngles = 6;
const int kPairOffsets = 20;
const int kPairRefinements = 3;
const double kPairOffsetLow = 0.001, kPairOffsetHigh = 4;
const double kPairGain = 1e-3;
const double kCutOffsetLow = 0.02, kCutOffsetHigh = 4;

} // namespace

PupilBounds::PupilBounds(const Prescription& lens, const MainLens& traced, double plane_z)
    : PupilBounds(lens, traced, plane_z, false)
{
}

PupilBounds::PupilBounds(const Prescription& lens, const MainLens& traced, double plane_z, bool tight)
    : plane_z_(plane_z), pupil_z_(traced.exit_pupil_centre().z), step_mm_(0), field_radius_mm_(0), reach_mm_(0)
{
    const Probe probe{traced, plane_z, pupil_z_};
    bool aspheric = false;
    for (const LensSurface& s : lens.surfaces)
        aspheric = aspheric || (!s.stop && s.is_aspheric());
    // The edge of the field: double a radius until no light passes, then bins up to it.
    double cx, radius;
    double edge = 0.5 * lens.surfaces.back().aperture_mm;
    for (int k = 0; k < kMaxFieldDoublings && bin_disc(lens, probe, edge, &cx, &radius); ++k) {
        edge *= 2;
        report_setup("pupil bounds", 0, kBins + 1);
    }
    step_mm_ = edge / kBins;
    std::vector<Bin> bins;
    for (int i = 0; i <= kBins; ++i) {
        report_setup("pupil bounds", i, kBins + 1);
        Bin bin{0, 0};
        if (bin_disc(lens, probe, i * step_mm_, &cx, &radius))
            bin = Bin{cx, radius};
        bins.push_back(bin);
        if (bin.radius > 0)
            field_radius_mm_ = (i + 1) * step_mm_;
    }
    report_setup("pupil bounds", kBins + 1, kBins + 1);
    for (int i = 0; i < kBins; ++i) {
        const Bin& a = bins[i];
        const Bin& b = bins[i + 1];
        Bin span{0, 0};
        if (a.radius > 0 && b.radius > 0)
            enclose(a.centre_x, a.radius, b.centre_x, b.radius, &span.centre_x, &span.radius);
        else if (a.radius > 0 || b.radius > 0)
            span = a.radius > 0 ? a : b;  // the field's edge lies between them: keep the lit one
        span.radius *= kMargin;
        if (aspheric)
            span.radius *= kAsphereMargin;
        spans_.push_back(span);
        reach_mm_ = std::max(reach_mm_, std::fabs(span.centre_x) + span.radius);
    }
    if (!tight)
        return;
    // Tight spans, kTightSplit to a bin. At each end of a span the region is measured (bin_disc,
    // tight): its disc and a polygon holding it. From the span's first lit end come
    // two cutting discs centred on the axis on either side of the region (a cat's eye is narrower
    // along x than its disc), each at the offset from the region's centre that leaves the least of
    // its disc within it; and, where it takes off at least kPairGain more of the area, a pair of
    // cutting discs off the axis, mirror images (the discs on the axis overhang a cat's eye's
    // corners); each holds the polygons of every end with the same centre offset. A disc with
    // its centre's y fixed is its x extent [lo, hi]; across the span each extent is taken linear
    // between its ends' (a cell meets a few per cent of a span), widened by the error a line can
    // make there: a quarter of the smaller of the extent's two second differences at the span's ends
    // (its |f''| h^2 / 8 bound, twice; the smaller, as a kink beside the span, where another
    // aperture begins to cut, shows in one of them only, a kink or a curvature within the span in
    // both), measured with the same offset at the neighbouring ends. Widened by kTightMargin (and
    // the cuts by kCutMargin) for what lies between the measured radii. Where only one end is lit,
    // a neighbour is dark (the field's edge) or lacks a polygon, the span is one disc holding its
    // lit ends' discs, as the bounds hold. Without polygons the cuts are the disc.
    struct Measured {
        bool lit;
        double centre_x, radius;
        std::vector<Vec2> hull;
    };
    tight_step_mm_ = step_mm_ / kTightSplit;
    const int tight_spans = kBins * kTightSplit;
    std::vector<Measured> at(size_t(tight_spans + 1));
    // The ends are measured on every hardware thread (each into its own slot, so the bounds do not
    // depend on the thread count); the calling thread reports progress, and when its reporter
    // throws (Ctrl-C) the others stop at their next end and the exception goes on once they have.
    std::atomic<int> next(0), done(0);
    std::atomic<bool> stop(false);
    std::exception_ptr thrown;
    run_on_threads(thread_count(0, size_t(tight_spans + 1)), [&](int t) {
        for (int i = next++; i <= tight_spans && !stop; i = next++) {
            if (t == 0) {
                try {
                    report_setup("tight pupil bounds", done, tight_spans + 1);
                } catch (...) {
                    thrown = std::current_exception();
                    stop = true;
                    break;
                }
            }
            Measured& m = at[size_t(i)];
            // Beyond the bounds' field no ray is traced (may_pass refuses them all).
            m.lit = !(i * tight_step_mm_ > field_radius_mm_) &&
                    bin_disc(lens, probe, i * tight_step_mm_, &m.centre_x, &m.radius, true, &m.hull) && m.radius > 0;
            ++done;
        }
    });
    if (thrown)
        std::rethrow_exception(thrown);
    report_setup("tight pupil bounds", tight_spans + 1, tight_spans + 1);
    const double aspheric_margin = aspheric ? kAsphereMargin : 1;
    // End -1, beyond the axis: the field point (-step, 0) sees end 1's region mirrored (x to -x), the
    // lens being one of revolution; so the first span's extents are linear between measured ends
    // with their curvature's allowance as every other span's are (a disc holding both ends' discs
    // before, which on the double Gauss's axis left 0.1 % of the radius: its region moves by some
    // 15 um in the first span).
    Measured beyond = at[1];
    beyond.centre_x = -beyond.centre_x;
    for (Vec2& p : beyond.hull)
        p.x = -p.x;
    auto end = [&](int i) -> const Measured& { return i < 0 ? beyond : at[size_t(i)]; };
    auto lit = [&](int i) { return i >= -1 && i <= tight_spans && end(i).lit; };
    // The x extent, at end i, of the region's disc (offset 0, no hull) or of a cutting disc centred
    // `offset` from the region's centre holding its polygon.
    auto extent = [&](int i, double offset, bool cut, double y, double* lo, double* hi) {
        const Measured& m = end(i);
        const double c = m.centre_x + offset;
        // Off the axis, the larger reach of the disc and its mirror image (the polygon is symmetric
        // about the axis only to the bisections' rounding).
        const double r = !cut ? m.radius : y != 0 ? reach_from_pair(m.hull, c, y) : reach_from(m.hull, c);
        *lo = c - r;
        *hi = c + r;
    };
    // The ramp of span i for one disc (cut: a cutting disc at `offset`); margin on its radius.
    auto ramp = [&](int i, double offset, bool cut, double margin, double y = 0) {
        Ramp out;
        out.y = y;
        double lo[4], hi[4];
        bool use[4];  // end i - 1 + k lit (and, for a cut, with its polygon)
        for (int k = 0; k < 4; ++k) {
            use[k] = lit(i - 1 + k) && !(cut && end(i - 1 + k).hull.empty());
            if (use[k])
                extent(i - 1 + k, offset, cut, y, &lo[k], &hi[k]);
        }
        if (use[0] && use[1] && use[2] && use[3]) {
            // The smaller of the two (see above).
            const double d_lo = std::min(std::fabs(lo[0] - 2 * lo[1] + lo[2]), std::fabs(lo[1] - 2 * lo[2] + lo[3]));
            const double d_hi = std::min(std::fabs(hi[0] - 2 * hi[1] + hi[2]), std::fabs(hi[1] - 2 * hi[2] + hi[3]));
            for (int e = 0; e < 2; ++e) {
                const double c = 0.5 * (lo[1 + e] + hi[1 + e]), r = 0.5 * (hi[1 + e] - lo[1 + e]) * margin;
                out.lo[e] = c - r - 0.25 * d_lo;
                out.hi[e] = c + r + 0.25 * d_hi;
            }
            out.lit = true;
            return out;
        }
        // One disc holding the lit ends' (widened by the margin).
        double c = 0, r = 0;
        bool any = false;
        for (int k = 1; k <= 2; ++k) {
            if (!use[k])
                continue;
            const double ck = 0.5 * (lo[k] + hi[k]), rk = 0.5 * (hi[k] - lo[k]);
            if (any)
                enclose(c, r, ck, rk, &c, &r);
            else {
                c = ck;
                r = rk;
            }
            any = true;
        }
        out.lit = any;
        out.lo[0] = out.lo[1] = c - r * margin;
        out.hi[0] = out.hi[1] = c + r * margin;
        return out;
    };
    for (int i = 0; i < tight_spans; ++i) {
        const int first = lit(i) ? i : i + 1;
        // Both ends' polygons measured (where lit): cutting discs.
        const bool polygons = lit(first) && !at[size_t(first)].hull.empty() && (!lit(i + 1) || !at[size_t(i + 1)].hull.empty());
        Ramp span = ramp(i, 0, false, kTightMargin * aspheric_margin);
        if (!span.lit) {
            // None measured lit: the bounds' own disc.
            const Bin& b = spans_[size_t(i / kTightSplit)];
            span.lit = b.radius > 0;
            span.lo[0] = span.lo[1] = b.centre_x - b.radius;
            span.hi[0] = span.hi[1] = b.centre_x + b.radius;
        }
        Ramp cut_lo = span, cut_hi = span;  // without polygons the cuts are the span's disc
        Ramp pair;                          // none (lit false) unless it pays
        if (!aspheric && polygons) {
            const Measured& m = at[size_t(first)];
            const double x0 = m.centre_x, r0 = m.radius;  // the disc
            // Each side's offset: kCutOffsets in geometric steps, then kCutRefinements rounds of the
            // two offsets a third of a step either side of the best.
            auto cut_offset = [&](double side) {
                double best = INFINITY, best_f = 0;
                auto consider = [&](double f) {
                    const double c = x0 + side * f * r0;
                    const Circle two[2] = {{x0, 0, r0}, {c, 0, reach_from(m.hull, c)}};
                    const double area = area_of(x0, two, 2);
                    if (area < best) {
                        best = area;
                        best_f = f;
                    }
                };
                const double ratio = std::pow(kCutOffsetHigh / kCutOffsetLow, 1 / (kCutOffsets - 1.0));
                for (int q = 0; q < kCutOffsets; ++q)
                    consider(kCutOffsetLow * std::pow(ratio, q));
                double step = std::log(ratio);
                for (int round = 0; round < kCutRefinements; ++round) {
                    step /= 3;
                    const double f = best_f;
                    consider(f * std::exp(-step));
                    consider(f * std::exp(step));
                }
                return best_f * r0;
            };
            const double off_lo = cut_offset(-1), off_hi = cut_offset(1);
            cut_lo = ramp(i, -off_lo, true, kTightMargin * kCutMargin);
            cut_hi = ramp(i, off_hi, true, kTightMargin * kCutMargin);
            // A pair of cutting discs off the axis, mirror images (where the region has corners, as a
            // cat's eye has, the discs on the axis overhang them): the direction and offset from the
            // region's centre that leave the least of the other three discs' intersection, if that
            // is less by kPairGain.
            Circle held[5] = {{x0, 0, r0}, {x0 - off_lo, 0, reach_from(m.hull, x0 - off_lo)},
                              {x0 + off_hi, 0, reach_from(m.hull, x0 + off_hi)}, {}, {}};
            const double without = area_of(x0, held, 3);
            double best = without * (1 - kPairGain), pair_x = 0, pair_y = 0;
            // A grid of directions and offsets, then kPairRefinements rounds of a 3 x 3 grid about
            // the best, each a third as wide.
            auto consider = [&](double angle, double f) {
                if (!(angle > 0 && angle < kPi))
                    return;
                const double px = x0 + f * r0 * std::cos(angle), py = f * r0 * std::sin(angle);
                const double reach = reach_from_pair(m.hull, px, py);
                held[3] = Circle{px, py, reach};
                held[4] = Circle{px, -py, reach};
                const double area = area_of(x0, held, 5);
                if (area < best) {
                    best = area;
                    pair_x = px - x0;
                    pair_y = py;
                }
            };
            const double angle_step = kPi / kPairAngles;
            const double ratio = std::pow(kPairOffsetHigh / kPairOffsetLow, 1 / (kPairOffsets - 1.0));
            for (int t = 1; t < kPairAngles; ++t)
                for (int q = 0; q < kPairOffsets; ++q)
                    consider(angle_step * t, kPairOffsetLow * std::pow(ratio, q));
            double d_angle = angle_step, d_log = std::log(ratio);
            for (int round = 0; round < kPairRefinements && pair_y > 0; ++round) {
                d_angle /= 3;
                d_log /= 3;
                const double angle = std::atan2(pair_y, pair_x), f = std::hypot(pair_x, pair_y) / r0;
                for (int a = -1; a <= 1; ++a)
                    for (int q = -1; q <= 1; ++q)
                        if (a != 0 || q != 0)
                            consider(angle + a * d_angle, f * std::exp(q * d_log));
            }
            if (pair_y > 0)
                pair = ramp(i, pair_x, true, kTightMargin * kCutMargin, pair_y);
        }
        tight_ramps_.push_back(span);
        cut_lo_ramps_.push_back(cut_lo);
        cut_hi_ramps_.push_back(cut_hi);
        if (pair.lit)
            pair.pair = true;
        pair_ramps_.push_back(pair.lit ? pair : span);
        pairs_ = pairs_ || pair.lit;
    }
}

PupilDisc PupilBounds::disc_for(Vec3 point) const
{
    // Not hypot: radii of millimetres neither overflow nor underflow, and this runs per sample.
    const double r = std::sqrt(point.x * point.x + point.y * point.y);
    const double at = r / step_mm_;
    if (!(at < kBins))
        return PupilDisc{Vec3{0, 0, pupil_z_}, 0};
    const Bin& span = spans_[size_t(at)];
    // The bin's +x disc turned to the point's azimuth.
    const double cx = r > 0 ? span.centre_x * point.x / r : span.centre_x;
    const double cy = r > 0 ? span.centre_x * point.y / r : 0;
    return PupilDisc{Vec3{cx, cy, pupil_z_}, span.radius};
}

PupilDisc PupilBounds::disc_holding(Vec3 centre, double radius, bool tight) const
{
    if (tight && has_tight())
        return holding(tight_ramps_, centre, radius, false);
    return holding(spans_, step_mm_, centre, radius);
}

int PupilBounds::discs_holding(Vec3 centre, double radius, PupilDisc out[kMaxDiscs]) const
{
    out[0] = disc_holding(centre, radius, true);
    if (!has_tight() || !(out[0].radius > 0) || !(std::sqrt(centre.x * centre.x + centre.y * centre.y) > std::fabs(radius)))
        return 1;
    out[1] = holding(cut_lo_ramps_, centre, radius, false);
    out[2] = holding(cut_hi_ramps_, centre, radius, false);
    if (!(out[1].radius > 0 && out[2].radius > 0))
        return 1;
    if (!pairs_)
        return 3;
    bool pair = false;  // some span the cell meets has a pair of its own (the others lend their disc)
    out[3] = holding(pair_ramps_, centre, radius, false, &pair);
    if (!pair)
        return 3;
    out[4] = holding(pair_ramps_, centre, radius, true);
    return out[3].radius > 0 && out[4].radius > 0 ? 5 : 3;
}

PupilDisc PupilBounds::holding(const std::vector<Bin>& spans, double step_mm, Vec3 centre, double radius) const
{
    // disc_for(q) lies in span floor(|q| / step) turned to q's azimuth. For |q - c| <= radius the
    // spans are those from (|c| - radius) to (|c| + radius), and the unit vector of q is within
    // 2 radius / |c| of c's (|q/|q| - c/|c|| <= 2 |q - c| / |c|; at most 2 anyway): so each span's
    // disc, turned to c's azimuth and widened by |centre_x| times that, holds the span's discs of
    // every such q. When the cell may hold the axis the discs are centred on it instead.
    const double r = std::sqrt(centre.x * centre.x + centre.y * centre.y);
    radius = std::fabs(radius);
    const int bins = int(spans.size());
    const double lo = std::max(0.0, r - radius) / step_mm, hi = (r + radius) / step_mm;
    if (!(lo < bins) || !std::isfinite(hi))
        return PupilDisc{Vec3{0, 0, pupil_z_}, 0};
    const int first = int(lo), last = std::min(bins - 1, int(hi));
    const bool about_axis = !(r > radius);
    const double turn = about_axis ? 0 : std::min(2.0, 2 * radius / r);
    double near = INFINITY, far = -INFINITY;  // along c's direction (or |.| about the axis)
    for (int k = first; k <= last; ++k) {
        const Bin& span = spans[size_t(k)];
        if (!(span.radius > 0))
            continue;
        if (about_axis) {
            near = std::min(near, -(std::fabs(span.centre_x) + span.radius));
            far = std::max(far, std::fabs(span.centre_x) + span.radius);
        } else {
            const double widened = span.radius + std::fabs(span.centre_x) * turn;
            near = std::min(near, span.centre_x - widened);
            far = std::max(far, span.centre_x + widened);
        }
    }
    if (!(far >= near))
        return PupilDisc{Vec3{0, 0, pupil_z_}, 0};
    const double along = 0.5 * (near + far);
    const double ux = about_axis ? 0 : centre.x / r, uy = about_axis ? 0 : centre.y / r;
    return PupilDisc{Vec3{along * ux, along * uy, pupil_z_}, 0.5 * (far - near)};
}

PupilDisc PupilBounds::holding(const std::vector<Ramp>& ramps, Vec3 centre, double radius, bool mirror,
                               bool* pair) const
{
    // As holding() over spans, with each span's disc taken over the part of it the cell's radii
    // cover (its extent at that part's ends: it is linear between), turned to the cell's azimuth
    // and widened by how far its centre turns across the cell; the discs of the spans met, enclosed.
    // A disc off the axis (Ramp::y; mirror: at -y) turns about the axis as its centre does.
    const double r = std::sqrt(centre.x * centre.x + centre.y * centre.y);
    radius = std::fabs(radius);
    const int spans = int(ramps.size());
    const double lo = std::max(0.0, r - radius) / tight_step_mm_, hi = (r + radius) / tight_step_mm_;
    if (!(lo < spans) || !std::isfinite(hi))
        return PupilDisc{Vec3{0, 0, pupil_z_}, 0};
    const int first = int(lo), last = std::min(spans - 1, int(hi));
    const bool about_axis = !(r > radius);
    // The unit vectors' distance itself, 2 sin(a / 2) for the largest angle a = asin(radius / r).
    const double turn = about_axis ? 0 : 2 * std::sin(0.5 * std::asin(radius / r)) * (1 + 1e-9);
    Circle held{0, 0, -1};
    for (int k = first; k <= last; ++k) {
        const Ramp& span = ramps[size_t(k)];
        if (!span.lit)
            continue;
        if (pair)
            *pair = *pair || span.pair;
        const double t0 = std::min(1.0, std::max(0.0, lo - k)), t1 = std::min(1.0, std::max(0.0, hi - k));
        const double x_lo = std::min(span.lo[0] + t0 * (span.lo[1] - span.lo[0]), span.lo[0] + t1 * (span.lo[1] - span.lo[0]));
        const double x_hi = std::max(span.hi[0] + t0 * (span.hi[1] - span.hi[0]), span.hi[0] + t1 * (span.hi[1] - span.hi[0]));
        Circle disc{0.5 * (x_lo + x_hi), mirror ? -span.y : span.y, 0.5 * (x_hi - x_lo)};
        if (about_axis)  // the cell may hold the axis: a disc about it holding every turn of this one
            disc = Circle{0, 0, std::hypot(disc.x, disc.y) + disc.r};
        else
            disc.r += std::hypot(disc.x, disc.y) * turn;
        held = held.r < 0 ? disc : enclose_circles(held, disc);
    }
    if (!(held.r >= 0))
        return PupilDisc{Vec3{0, 0, pupil_z_}, 0};
    // (x, y) of the +x frame turned to the cell's azimuth.
    const double ux = about_axis ? 1 : centre.x / r, uy = about_axis ? 0 : centre.y / r;
    return PupilDisc{Vec3{held.x * ux - held.y * uy, held.x * uy + held.y * ux, pupil_z_}, held.r * (1 + 1e-12)};
}

bool PupilBounds::may_pass(Vec3 point, Vec3 direction) const
{
    // The ray's line where it crosses the bounds' plane: the same line, and only air lies between.
    Vec3 from = point;
    if (point.z != plane_z_) {
        const double s = (plane_z_ - point.z) / direction.z;
        if (!std::isfinite(s))
            return true;
        from = Vec3{point.x + s * direction.x, point.y + s * direction.y, plane_z_};
    }
    const double t = (pupil_z_ - from.z) / direction.z;
    if (!(t > 0) || !std::isfinite(t))
        return true;
    const PupilDisc disc = disc_for(from);
    const double x = from.x + t * direction.x - disc.centre.x;
    const double y = from.y + t * direction.y - disc.centre.y;
    return x * x + y * y <= disc.radius * disc.radius;
}

} // namespace plenoptic
