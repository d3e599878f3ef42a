// SPDX-License-Identifier: AGPL-3.0-or-later
// Samples where light passes (see the header).

#include "plenoptic/camera/aim.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "plenoptic/array/microlens_array.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/pupil_bounds.h"

namespace plenoptic {

namespace {

// Relative widening of every disc: its centre and radius come from sums of terms up to this many
// times larger than rounding (1e-16 of them), so the disc still holds what the exact one holds.
const double kRoundingMargin = 1e-9;
const double kSqrt3 = 1.7320508075688772935;

} // namespace

bool camera_can_aim(const PlenopticCamera& m)
{
    // Lenses tilted by their errors and the unbent light of a clear gap (fill_factor) leave the
    // thin lens's affine map; a mask would only block more, but is kept with the gap for simplicity.
    return m.lens && m.lens->forms_image() && m.array.grid != GridType::None && m.array.microlens &&
           m.array.microlens->aims() && !m.array.pose.tilted && !(m.array.errors && m.array.errors->tilts()) &&
           !(m.array.fill_factor < 1) && m.sampling.samples_max > 1;
}

bool lens_aim(const PlenopticCamera& m, LensIndex lens, LensAim* out)
{
    const Vec3 centre = m.array.centre_mm(lens);
    const double circumradius = m.array.cell_circumradius_mm;
    PupilDisc disc;
    if (m.pupil_bounds) {
        // The bounds are for points of one plane: a lens off it (displaced along the axis) is not aimed at.
        if (!(std::fabs(centre.z - m.pupil_bounds->plane_z()) <= 1e-9 * (1 + std::fabs(centre.z))))
            return false;
        PupilDisc discs[3];
        const int count = m.pupil_bounds->discs_holding(centre, circumradius, discs);
        disc = discs[0];
        out->cuts = count == 3 ? 2 : 0;
        for (int k = 0; k < out->cuts; ++k) {
            const Vec3 q = m.array.to_local(discs[k + 1].centre);
            out->cut_m[k] = Vec2{q.x, q.y};
            out->cut_rho[k] = discs[k + 1].radius;
            if (!(is_finite(out->cut_m[k]) && out->cut_rho[k] >= 0 && std::isfinite(out->cut_rho[k])))
                return false;
        }
    } else if (m.lens->traced()) {
        return false;
    } else {
        // An ideal lens blocks exactly outside its exit pupil (the thin lens's aperture in its plane).
        disc = PupilDisc{m.lens->exit_pupil_centre(), m.lens->exit_pupil_radius()};
    }
    if (!m.pupil_bounds)
        out->cuts = 0;
    const Vec3 c = m.array.to_local(centre);
    const Vec3 d = m.array.to_local(disc.centre);
    out->lens = lens;
    out->c = Vec2{c.x, c.y};
    out->z = c.z;
    out->f = m.array.focal_length_mm(lens);
    out->circumradius = circumradius;
    out->Z = d.z - c.z;
    out->m = Vec2{d.x, d.y};
    out->rho = disc.radius;
    return out->Z > 0 && std::isfinite(out->Z) && out->f != 0 && std::isfinite(out->f) && out->rho >= 0 &&
           std::isfinite(out->rho) && is_finite(out->m) && is_finite(out->c);
}

namespace {

AimDisc sensor_disc(const LensAim& a, double d, Vec2 m, double rho)
{
    // |(Z/d) s - c (1 + Z/d) + m| <= rho + |g| R, divided by Z/d.
    const double g = 1 + a.Z / d - a.Z / a.f;
    const double k = d / a.Z;
    const Vec2 shift{(a.c.x - m.x) * k, (a.c.y - m.y) * k};
    const double radius = (rho + std::fabs(g) * a.circumradius) * k;
    const double slack = kRoundingMargin * (std::fabs(shift.x) + std::fabs(shift.y) + radius + std::fabs(a.c.x) +
                                            std::fabs(a.c.y));
    return AimDisc{Vec2{a.c.x + shift.x, a.c.y + shift.y}, radius * (1 + kRoundingMargin) + slack};
}

AimDisc cell_disc(const LensAim& a, Vec3 s, Vec2 m, double rho)
{
    // g h - (Z/d) s + (Z/f) c within rho of m; from the lens's centre: h - c within rho / |g| of
    // (m - c + (Z/d) (s - c)) / g.
    const double d = a.z - s.z;
    const double g = 1 + a.Z / d - a.Z / a.f;
    if (!(g != 0) || !std::isfinite(g))
        return AimDisc{Vec2{0, 0}, std::numeric_limits<double>::infinity()};
    const double k = a.Z / d;
    const double x = m.x - a.c.x + k * (s.x - a.c.x), y = m.y - a.c.y + k * (s.y - a.c.y);
    const double slack = kRoundingMargin * (std::fabs(x) + std::fabs(y) + rho) / std::fabs(g);
    return AimDisc{Vec2{x / g, y / g}, rho / std::fabs(g) * (1 + kRoundingMargin) + slack};
}

} // namespace

AimDisc lit_sensor_disc(const LensAim& a, double d)
{
    return sensor_disc(a, d, a.m, a.rho);
}

AimDisc lit_sensor_cut(const LensAim& a, double d, int k)
{
    return sensor_disc(a, d, a.cut_m[k], a.cut_rho[k]);
}

AimDisc lit_cell_disc(const LensAim& a, Vec3 s)
{
    return cell_disc(a, s, a.m, a.rho);
}

AimDisc lit_cell_cut(const LensAim& a, Vec3 s, int k)
{
    return cell_disc(a, s, a.cut_m[k], a.cut_rho[k]);
}

double cell_half_height(GridType grid, double pitch_mm, double x)
{
    const double half = 0.5 * pitch_mm;
    if (!(std::fabs(x) <= half))
        return -1;
    if (grid != GridType::Hexagonal)
        return half;
    // Pointy-topped hexagon (corners at +-R on the y axis, R = p / sqrt 3), sides at x = +-p/2.
    return pitch_mm / kSqrt3 - std::fabs(x) / kSqrt3;
}

namespace {

// A lens's lit_sensor_disc in pixel coordinates (corner convention: Sensor::point): an axis-aligned
// ellipse; false when it is not finite.
struct PixelEllipse {
    double cu, cv, au, av;
};

bool pixel_ellipse(const PlenopticCamera& m, const LensAim& a, const Vec3& s, PixelEllipse* e, int cut = -1)
{
    const double d = a.z - s.z;
    if (!(d > 0))
        return false;
    const AimDisc disc = cut < 0 ? lit_sensor_disc(a, d) : lit_sensor_cut(a, d, cut);
    const Vec3 q = m.array.to_optics(Vec3{disc.centre.x, disc.centre.y, s.z});
    const Sensor& sensor = m.sensor;
    const double px = sensor.pixel_size_mm[0], py = sensor.pixel_size_mm[1];
    e->cu = 0.5 * sensor.film.width - (q.x - sensor.offset_mm[0]) / px;
    e->cv = 0.5 * sensor.film.height + (q.y - sensor.offset_mm[1]) / py;
    e->au = disc.radius / px;
    e->av = disc.radius / py;
    return std::isfinite(e->cu) && std::isfinite(e->cv) && e->au >= 0 && e->av >= 0 && std::isfinite(e->au) &&
           std::isfinite(e->av);
}

bool holds_pixel(const PixelEllipse& e, int i, int j)
{
    if (!(e.au > 0 && e.av > 0))
        return false;
    for (int b = 0; b < 2; ++b)
        for (int a = 0; a < 2; ++a) {
            const double du = (i + a - e.cu) / e.au, dv = (j + b - e.cv) / e.av;
            if (!(du * du + dv * dv <= 1))
                return false;
        }
    return true;
}

// The ellipse's chord at x (half length; negative when x is outside it).
double chord(const PixelEllipse& e, double x)
{
    const double t = (x - e.cu) / e.au;
    return t * t <= 1 ? e.av * std::sqrt(1 - t * t) : -1;
}

// Up to kMaxParts intervals, merged into a union that can be sampled uniformly.
const int kMaxParts = 9;
struct Intervals {
    double lo[kMaxParts], hi[kMaxParts];
    int count = 0;
    void add(double a, double b)
    {
        if (!(b > a))
            return;
        int k = count++;
        while (k > 0 && lo[k - 1] > a) {  // keep them sorted by their start
            lo[k] = lo[k - 1];
            hi[k] = hi[k - 1];
            --k;
        }
        lo[k] = a;
        hi[k] = b;
    }
    // Merges overlapping intervals; returns the union's length.
    double merge()
    {
        int out = 0;
        for (int k = 0; k < count; ++k) {
            if (out > 0 && lo[k] <= hi[out - 1]) {
                if (hi[k] > hi[out - 1])
                    hi[out - 1] = hi[k];
            } else {
                lo[out] = lo[k];
                hi[out] = hi[k];
                ++out;
            }
        }
        count = out;
        double total = 0;
        for (int k = 0; k < count; ++k)
            total += hi[k] - lo[k];
        return total;
    }
    // The point at fraction t of the merged union's length.
    double at(double t, double total) const
    {
        double left = t * total;
        for (int k = 0; k < count; ++k) {
            const double length = hi[k] - lo[k];
            if (left < length || k == count - 1)
                return lo[k] + (left < length ? left : length);
            left -= length;
        }
        return lo[0];
    }
};

} // namespace

namespace {

// What a camera's aim depends on, to tell a cached plan's camera from another (a camera copied or
// made at the same address differs in one of these when its geometry does).
struct CameraKey {
    const PlenopticCamera* camera;
    const void* parts[4];
    double geometry[12];
    bool operator==(const CameraKey& o) const
    {
        if (camera != o.camera)
            return false;
        for (int k = 0; k < 4; ++k)
            if (parts[k] != o.parts[k])
                return false;
        for (int k = 0; k < 12; ++k)
            if (!(geometry[k] == o.geometry[k]))
                return false;
        return true;
    }
};

CameraKey key_of(const PlenopticCamera& m)
{
    const Sensor& s = m.sensor;
    const ArrayPose& pose = m.array.pose;
    return CameraKey{&m,
                     {m.lens.get(), m.array.microlens.get(), m.pupil_bounds.get(), m.array.errors.get()},
                     {s.z_mm, s.pixel_size_mm[0], s.pixel_size_mm[1], s.offset_mm[0], s.offset_mm[1], double(s.film.width),
                      double(s.film.height), pose.centre_mm.x, pose.centre_mm.y, pose.centre_mm.z, pose.rotation.m[0][0],
                      pose.rotation.m[0][1]}};
}

// A pixel's aim, worked out once for all its samples: its points are uniform (the whole pixel may be
// lit), none (no light reaches it), or drawn from the union of `count` ellipses, whose x ranges
// within the pixel are `xs` (of total length `width`).
struct PixelPlan {
    enum Kind { Uniform, Dark, Aimed } kind;
    bool forced;
    LensIndex lens;
    int count;
    PixelEllipse ellipses[kMaxParts];
    // Behind a traced lens: lens k's light lands only in ellipses[k] and its cuts[k][0 .. cut_count[k]-1].
    int cut_count[kMaxParts];
    PixelEllipse cuts[kMaxParts][2];
    Intervals xs;
    double width;
};

// A lens's ellipse and its cuts, for the pixel's plan (false when one is not finite).
bool lens_ellipses(const PlenopticCamera& m, const LensAim& a, const Vec3& s, PixelPlan* plan, int k)
{
    plan->cut_count[k] = a.cuts;
    for (int c = 0; c < a.cuts; ++c)
        if (!pixel_ellipse(m, a, s, &plan->cuts[k][c], c))
            return false;
    return true;
}

void plan_pixel(const PlenopticCamera& m, int i, int j, const LensIndex* forced, PixelPlan* plan)
{
    plan->kind = PixelPlan::Uniform;
    plan->forced = forced != nullptr;
    plan->count = 0;
    for (int k = 0; k < kMaxParts; ++k)
        plan->cut_count[k] = 0;
    const Vec3 middle = m.sensor.point(i + 0.5, j + 0.5);
    LensIndex lens;
    if (forced) {
        lens = *forced;
    } else {
        const OwnLens own = own_lens(m, middle);
        if (!own.found)
            return;
        lens = own.lens;
    }
    plan->lens = lens;
    LensAim a;
    PixelEllipse own_ellipse;
    const Vec3 s = m.array.to_local(middle);
    if (!lens_aim(m, lens, &a) || !pixel_ellipse(m, a, s, &own_ellipse) || !lens_ellipses(m, a, s, plan, 0))
        return;  // the whole pixel may be lit: its own points, as the uniform samples
    bool held = holds_pixel(own_ellipse, i, j);
    for (int c = 0; c < plan->cut_count[0]; ++c)
        held = held && holds_pixel(plan->cuts[0][c], i, j);
    if (held)
        return;
    const int own_cuts = plan->cut_count[0];
    const PixelEllipse own_cut[2] = {plan->cuts[0][0], plan->cuts[0][1]};
    // The ellipses that can light the pixel: the forced lens's; or, for the pixel's own lenses, the
    // lens of its centre and its neighbours (the lattice cells a pixel far smaller than a cell can
    // meet: checked below).
    PixelEllipse* ellipses = plan->ellipses;
    int count = 0;
    if (forced) {
        ellipses[count++] = own_ellipse;
    } else {
        // Through the exit pupil's centre e the pixel projects onto the array scaled by
        // (array - e) / (sensor - e); a point within delta of the centre's projection belongs to
        // the centre's lens or a neighbour while delta < 0.25 pitch (the next ring is at least
        // 1.15 pitch from any point of the cell, the cell's corners at most 0.71 pitch), less
        // 1.5 times the farthest a lens is displaced from its lattice place (its errors).
        const Vec3 e = m.lens->exit_pupil_centre();
        const double scale = (m.array.pose.centre_mm.z - e.z) / (m.sensor.z_mm - e.z);
        const double delta = 0.5 * std::hypot(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1]) * std::fabs(scale);
        const double shift = m.array.errors ? m.array.errors->max_shift_mm() : 0;
        if (!(delta + 1.5 * shift < 0.25 * m.array.pitch_mm))
            return;
        const GridType grid = m.array.grid;
        const std::int64_t skew = skew_k(grid, lens);
        for (int dl = -1; dl <= 1; ++dl)
            for (int dk = -1; dk <= 1; ++dk) {
                if (grid == GridType::Hexagonal && std::abs(dk + dl) > 1)
                    continue;  // not a neighbour in skew indices
                const LensIndex other = from_skew(grid, skew + dk, lens.l + dl);
                PixelEllipse e;
                if (dk == 0 && dl == 0) {
                    e = own_ellipse;
                    plan->cut_count[count] = own_cuts;
                    plan->cuts[count][0] = own_cut[0];
                    plan->cuts[count][1] = own_cut[1];
                } else if (!lens_aim(m, other, &a) || !pixel_ellipse(m, a, s, &e) || !lens_ellipses(m, a, s, plan, count))
                    return;
                ellipses[count++] = e;
            }
    }
    plan->count = count;
    // x: the union over the ellipses of the x range of the pixel's part in each (the ellipse's at
    // the pixel's row nearest its centre).
    // With cuts, the intersection of the x ranges of the pixel's part in each (which holds the x
    // range of the pixel's part in their intersection).
    plan->xs = Intervals();
    for (int k = 0; k < count; ++k) {
        double lo = i, hi = i + 1;
        bool none = false;
        for (int c = -1; c < plan->cut_count[k]; ++c) {
            const PixelEllipse& e = c < 0 ? ellipses[k] : plan->cuts[k][c];
            const double row = e.cv < j ? j : (e.cv > j + 1 ? j + 1 : e.cv);
            const double t = (row - e.cv) / e.av;
            if (!(t * t <= 1)) {
                none = true;
                break;
            }
            const double reach = e.au * std::sqrt(1 - t * t);
            lo = std::max<double>(lo, e.cu - reach);
            hi = std::min<double>(hi, e.cu + reach);
        }
        if (!none)
            plan->xs.add(lo, hi);
    }
    plan->width = plan->xs.merge();
    plan->kind = plan->width > 0 ? PixelPlan::Aimed : PixelPlan::Dark;
}

// The plan of the pixel last asked for on this thread (samples come pixel by pixel).
struct CachedPlan {
    bool valid = false;
    CameraKey key;
    int i = 0, j = 0;
    bool forced = false;
    LensIndex forced_lens{0, 0};
    PixelPlan plan;
};

} // namespace

PixelAim aim_pixel(const PlenopticCamera& m, int i, int j, double pixel_u, double pixel_v, const LensIndex* forced)
{
    PixelAim out{i + pixel_u, j + pixel_v, 1, false, LensIndex{0, 0}, true};
    static thread_local CachedPlan cache;
    const CameraKey key = key_of(m);
    if (!(cache.valid && cache.i == i && cache.j == j && cache.forced == (forced != nullptr) &&
          (!forced || cache.forced_lens == *forced) && cache.key == key)) {
        plan_pixel(m, i, j, forced, &cache.plan);
        cache.valid = true;
        cache.key = key;
        cache.i = i;
        cache.j = j;
        cache.forced = forced != nullptr;
        if (forced)
            cache.forced_lens = *forced;
    }
    const PixelPlan& plan = cache.plan;
    if (plan.kind == PixelPlan::Uniform)
        return out;
    if (plan.forced) {
        out.lens_forced = true;
        out.lens = plan.lens;
    }
    if (plan.kind == PixelPlan::Dark) {
        out.passed = false;  // no light reaches the pixel
        return out;
    }
    const double x = plan.xs.at(pixel_u, plan.width);
    // y: the union of the chords at x within the pixel's rows.
    Intervals ys;
    for (int k = 0; k < plan.count; ++k) {
        const double half = chord(plan.ellipses[k], x);
        if (!(half >= 0))
            continue;
        double lo = std::max<double>(j, plan.ellipses[k].cv - half), hi = std::min<double>(j + 1, plan.ellipses[k].cv + half);
        for (int c = 0; c < plan.cut_count[k]; ++c) {
            const PixelEllipse& e = plan.cuts[k][c];
            const double h = chord(e, x);
            lo = h >= 0 ? std::max(lo, e.cv - h) : INFINITY;
            hi = std::min(hi, e.cv + h);
        }
        ys.add(lo, hi);
    }
    const double height = ys.merge();
    if (!(height > 0)) {
        out.passed = false;
        return out;
    }
    out.pu = x;
    out.pv = ys.at(pixel_v, height);
    out.weight = plan.width * height;
    return out;
}

ArrayRay aimed_cell_ray(const PlenopticCamera& m, const Vec3& p, LensIndex lens, double u, double v, double* weight)
{
    *weight = 1;
    const MicrolensArray& array = m.array;
    // The lens last aimed at on this thread (a pixel's samples mostly go through one lens).
    struct CachedLens {
        bool valid = false, aimed = false;
        CameraKey key;
        LensAim aim;
    };
    static thread_local CachedLens cache;
    const CameraKey key = key_of(m);
    if (!(cache.valid && cache.aim.lens == lens && cache.key == key)) {
        cache.aimed = lens_aim(m, lens, &cache.aim);
        cache.aim.lens = lens;
        cache.key = key;
        cache.valid = true;
    }
    if (!cache.aimed)
        return array.microlens->sample_ray(array, p, lens, u, v);
    const LensAim& a = cache.aim;
    const Vec3 s = array.to_local(p);
    if (!(a.z - s.z > 0))
        return array.microlens->sample_ray(array, p, lens, u, v);
    const AimDisc disc = lit_cell_disc(a, s);
    const GridType grid = array.grid;
    const double pitch = array.pitch_mm;
    const double area = grid == GridType::Hexagonal ? 0.5 * kSqrt3 * pitch * pitch : pitch * pitch;
    if (a.cuts > 0) {
        // The cell's part in the disc and both cuts: x uniform over their common x range, y over
        // the chords' intersection at x.
        AimDisc discs[3] = {disc, lit_cell_cut(a, s, 0), lit_cell_cut(a, s, 1)};
        bool whole = true;
        double lo = -0.5 * pitch, hi = 0.5 * pitch;
        for (const AimDisc& d : discs) {
            if (!(d.radius < std::numeric_limits<double>::infinity()))
                continue;
            whole = whole && std::sqrt(d.centre.x * d.centre.x + d.centre.y * d.centre.y) + a.circumradius <= d.radius;
            lo = std::max(lo, d.centre.x - d.radius);
            hi = std::min(hi, d.centre.x + d.radius);
        }
        if (whole)
            return array.microlens->sample_ray(array, p, lens, u, v);  // the whole cell may pass
        if (!(hi > lo))
            return ArrayRay{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}};
        const double x = lo + u * (hi - lo);
        const double half = cell_half_height(grid, pitch, x);
        double y0 = -half, y1 = half;
        for (const AimDisc& d : discs) {
            if (!(d.radius < std::numeric_limits<double>::infinity()))
                continue;
            const double t = (x - d.centre.x) / d.radius;
            const double c = d.radius * std::sqrt(t < 1 ? 1 - t * t : 0);
            y0 = std::max(y0, d.centre.y - c);
            y1 = std::min(y1, d.centre.y + c);
        }
        if (!(y1 > y0))
            return ArrayRay{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}};
        *weight = (hi - lo) * (y1 - y0) / area;
        return array.microlens->cell_ray(array, p, lens, Vec2{x, y0 + v * (y1 - y0)});
    }
    if (!(disc.radius < std::numeric_limits<double>::infinity()) ||
        std::sqrt(disc.centre.x * disc.centre.x + disc.centre.y * disc.centre.y) + a.circumradius <= disc.radius)
        return array.microlens->sample_ray(array, p, lens, u, v);  // the whole cell may pass
    const ChordSample sample = sample_chords(
        -0.5 * pitch, 0.5 * pitch, disc.centre.x - disc.radius, disc.centre.x + disc.radius,
        [grid, pitch](double x, double* y0, double* y1) {
            const double half = cell_half_height(grid, pitch, x);
            *y0 = -half;
            *y1 = half;
        },
        disc.centre, disc.radius, disc.radius, area, u, v);
    if (!sample.passed)
        return ArrayRay{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}};
    *weight = sample.weight;
    return array.microlens->cell_ray(array, p, lens, sample.point);
}

} // namespace plenoptic
