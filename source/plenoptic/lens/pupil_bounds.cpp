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
#include <cmath>
#include <cstdlib>

#include "plenoptic/core/setup_progress.h"

namespace plenoptic {

namespace {

const int kBins = 48;            // field radii sampled from the axis to the edge of the field
const int kGrid = 48;            // grid points a side over the search square
const int kAzimuths = 64;        // boundary directions refined by bisection
const int kBisections = 24;      // steps of each bisection (2^-24 of the grid radius)
const double kMargin = 1.01;     // radius margin for the bins, and again for points between them
const int kMaxFieldDoublings = 60;
// Tight discs (for aiming): boundary directions, field radii measured per span besides its two
// bins, and the margin on each span's radius for what lies between the measured radii (validated
// by brute force in pupil_bounds_test).
const int kTightAzimuths = 256;
const int kTightBetween = 3;
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
            double inside = 0, outside = grid_radius + std::fabs(x0 - cx);
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
    if (tight && probe.passes(r, cx, 0)) {
        // The grid's centre is off by up to a grid cell (which made neighbouring radii's discs
        // jump): measured from the middle of the region's x extent instead, found by bisection
        // along the x axis (the region is symmetric about it, so a convex one is widest there).
        double ends[2];
        for (int side = 0; side < 2; ++side) {
            double inside = 0, outside = grid_radius;
            for (int s = 0; s < kBisections; ++s) {
                const double mid = 0.5 * (inside + outside);
                if (probe.passes(r, cx + (side ? mid : -mid), 0))
                    inside = mid;
                else
                    outside = mid;
            }
            ends[side] = cx + (side ? outside : -outside);
        }
        x0 = 0.5 * (ends[0] + ends[1]);
    }
    double refined = refine(x0, &x_lo, &x_hi, tight ? &corners : nullptr);
    if (!std::isfinite(refined) && x0 != cx) {
        x0 = cx;
        refined = refine(x0, &x_lo, &x_hi, &corners);
    }
    if (!std::isfinite(refined))
        refined = grid_radius;  // not star-shaped about its centre: keep the grid's bound
    *centre_x = x0;
    if (hull) {
        hull->clear();
        if (tight && refined < grid_radius)
            hull->swap(corners);  // empty: no polygon (the region was not measured star-shaped)
    }
    // Tight: the measured boundary (the bisection's outer ends, the convex allowance between the
    // directions); the bounds add kMargin.
    *radius = std::min(grid_radius, tight ? refined : refined * kMargin);
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
    double reach = 0;
    for (const Vec2& p : hull)
        reach = std::max(reach, std::hypot(p.x - x, p.y));
    return reach;
}

// The area of the part of the disc (c0, r0) within the disc (c1, r1), both on the x axis and both
// holding (x0, 0) (a sum over directions from it).
double area_within(double x0, double c0, double r0, double c1, double r1)
{
    const int n = 256;
    double area = 0;
    for (int k = 0; k < n; ++k) {
        const double a = 2 * kPi * (k + 0.5) / n, dx = std::cos(a);
        double t = INFINITY;
        for (const double* d : {&c0, &c1}) {
            const double c = *d, r = d == &c0 ? r0 : r1;
            const double b = (x0 - c) * dx, q = (x0 - c) * (x0 - c) - r * r;  // |x0 + t u - c|^2 = r^2
            t = std::min(t, -b + std::sqrt(std::max(0.0, b * b - q)));
        }
        area += 0.5 * t * t;
    }
    return area * 2 * kPi / n;
}

// Offsets of the cutting discs' centres from the region's, in units of its disc's radius.
const double kCutOffsets[] = {0.05, 0.1, 0.2, 0.3, 0.5, 0.75, 1, 1.5, 2, 3};

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
    // Tight spans: the tight discs at both bins and kTightBetween radii between them, enclosed,
    // widened by kTightMargin. Where no light passes at a measured radius but does at another of
    // the span, the span holds the lit ones (as the bounds do at the field's edge). And two
    // cutting discs per span, centred on either side of the region along x (a cat's eye is
    // narrower along x than its disc), each holding the measured polygons of the span's radii:
    // the offset from the region's centre that leaves the least of the middle radius's disc
    // within the cut, the same offset at every radius of the span.
    struct Measured {
        bool lit;
        double centre_x, radius;
        std::vector<Vec2> hull;
    };
    std::vector<Measured> at_bins(kBins + 1);
    for (int i = 0; i <= kBins; ++i) {
        Measured& m = at_bins[size_t(i)];
        m.lit = bins[size_t(i)].radius > 0 && bin_disc(lens, probe, i * step_mm_, &m.centre_x, &m.radius, true, &m.hull);
    }
    for (int i = 0; i < kBins; ++i) {
        std::vector<Measured> at(size_t(kTightBetween + 2));
        for (int k = 0; k <= kTightBetween + 1; ++k) {
            if (k == 0)
                at[0] = at_bins[size_t(i)];
            else if (k == kTightBetween + 1)
                at[size_t(k)] = at_bins[size_t(i + 1)];
            else {
                Measured& m = at[size_t(k)];
                m.lit = bin_disc(lens, probe, (i + double(k) / (kTightBetween + 1)) * step_mm_, &m.centre_x, &m.radius,
                                 true, &m.hull);
            }
        }
        Bin span{0, 0}, cut_lo{0, 0}, cut_hi{0, 0};
        bool any = false, cuts = true;
        for (const Measured& m : at) {
            if (!m.lit || !(m.radius > 0))
                continue;
            if (any)
                enclose(span.centre_x, span.radius, m.centre_x, m.radius, &span.centre_x, &span.radius);
            else
                span = Bin{m.centre_x, m.radius};
            any = true;
            cuts = cuts && !m.hull.empty();
        }
        // The offsets, chosen at the middle lit radius.
        double off_lo = 0, off_hi = 0;
        if (any && cuts) {
            const Measured* middle = nullptr;  // the lit radius nearest the middle
            for (int k = 0; k <= kTightBetween + 1; ++k)
                if (at[size_t(k)].lit && at[size_t(k)].radius > 0 &&
                    (!middle || std::abs(2 * k - kTightBetween - 1) < std::abs(2 * int(middle - at.data()) - kTightBetween - 1)))
                    middle = &at[size_t(k)];
            const double x0 = middle->centre_x, r0 = middle->radius;
            double best_lo = INFINITY, best_hi = INFINITY;
            for (double f : kCutOffsets) {
                const double lo_c = x0 - f * r0, hi_c = x0 + f * r0;
                const double lo_a = area_within(x0, x0, r0, lo_c, reach_from(middle->hull, lo_c));
                const double hi_a = area_within(x0, x0, r0, hi_c, reach_from(middle->hull, hi_c));
                if (lo_a < best_lo) {
                    best_lo = lo_a;
                    off_lo = f * r0;
                }
                if (hi_a < best_hi) {
                    best_hi = hi_a;
                    off_hi = f * r0;
                }
            }
            bool first = true;
            for (const Measured& m : at) {
                if (!m.lit || !(m.radius > 0))
                    continue;
                const Bin lo{m.centre_x - off_lo, reach_from(m.hull, m.centre_x - off_lo)};
                const Bin hi{m.centre_x + off_hi, reach_from(m.hull, m.centre_x + off_hi)};
                if (first) {
                    cut_lo = lo;
                    cut_hi = hi;
                } else {
                    enclose(cut_lo.centre_x, cut_lo.radius, lo.centre_x, lo.radius, &cut_lo.centre_x, &cut_lo.radius);
                    enclose(cut_hi.centre_x, cut_hi.radius, hi.centre_x, hi.radius, &cut_hi.centre_x, &cut_hi.radius);
                }
                first = false;
            }
        }
        span.radius *= kTightMargin;
        cut_lo.radius *= kTightMargin * kCutMargin;
        cut_hi.radius *= kTightMargin * kCutMargin;
        if (aspheric) {
            span.radius *= kAsphereMargin;
            cut_lo.radius *= kAsphereMargin;
            cut_hi.radius *= kAsphereMargin;
        }
        if (!(span.radius > 0))
            span = spans_[size_t(i)];  // none measured lit: the bounds' own disc
        // Without polygons (a region not measured star-shaped) the cuts are the span's disc.
        if (!(cut_lo.radius > 0 && cut_hi.radius > 0) || aspheric)
            cut_lo = cut_hi = span;
        tight_spans_.push_back(span);
        cut_lo_spans_.push_back(cut_lo);
        cut_hi_spans_.push_back(cut_hi);
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
        return holding(tight_spans_, step_mm_, centre, radius, true);
    return holding(spans_, step_mm_, centre, radius, false);
}

int PupilBounds::discs_holding(Vec3 centre, double radius, PupilDisc out[3]) const
{
    out[0] = disc_holding(centre, radius, true);
    if (!has_tight() || !(out[0].radius > 0) || !(std::sqrt(centre.x * centre.x + centre.y * centre.y) > std::fabs(radius)))
        return 1;
    out[1] = holding(cut_lo_spans_, step_mm_, centre, radius, true);
    out[2] = holding(cut_hi_spans_, step_mm_, centre, radius, true);
    return out[1].radius > 0 && out[2].radius > 0 ? 3 : 1;
}

PupilDisc PupilBounds::holding(const std::vector<Bin>& spans, double step_mm, Vec3 centre, double radius,
                               bool exact_turn) const
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
    // Tight: the unit vectors' distance itself, 2 sin(a / 2) for the largest angle a = asin(radius / r).
    const double turn = about_axis ? 0
                        : exact_turn ? 2 * std::sin(0.5 * std::asin(radius / r)) * (1 + 1e-9)
                                     : std::min(2.0, 2 * radius / r);
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

bool PupilBounds::may_pass(Vec3 point, Vec3 direction) const
{
    const double t = (pupil_z_ - point.z) / direction.z;
    if (!(t > 0) || !std::isfinite(t))
        return true;
    const PupilDisc disc = disc_for(point);
    const double x = point.x + t * direction.x - disc.centre.x;
    const double y = point.y + t * direction.y - disc.centre.y;
    return x * x + y * y <= disc.radius * disc.radius;
}

} // namespace plenoptic
