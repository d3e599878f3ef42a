// SPDX-License-Identifier: AGPL-3.0-or-later
// Ray generation through ideal thin lenses and pinholes, chief rays, overlap lenses.

#include "plenoptic/camera/rays.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "plenoptic/camera/aim.h"
#include "plenoptic/camera/camera_key.h"
#include "plenoptic/camera/radiometry.h"
#include "plenoptic/camera/rays_internal.h"

namespace plenoptic {

namespace detail {

// Intersection of the line (main-lens centre -> p), or the vertical line through p when there is
// no main lens, with the array plane; array-local coordinates.
bool project_to_array(const PlenopticCamera& m, Vec3 p, Vec2* local)
{
    const Vec3 n = m.array.pose.normal;
    Vec3 q;
    if (!m.lens) {
        if (!(n.z > 0))
            return false;
        q = Vec3{p.x, p.y, p.z + dot(n, m.array.pose.centre_mm - p) / n.z};
    } else {
        // The line from the exit pupil's centre e through p: q = e + s (p - e).
        const Vec3 e = m.lens->exit_pupil_centre();
        const double along = dot(n, p - e);
        const double s = dot(n, m.array.pose.centre_mm - e) / along;
        if (!(s > 0) || !std::isfinite(s))
            return false;
        q = e + s * (p - e);
    }
    const Vec3 l = m.array.to_local(q);
    *local = Vec2{l.x, l.y};
    return is_finite(*local);
}

} // namespace detail

namespace {

using detail::project_to_array;

// The ray into the scene as the renderer takes it; false when it does not pass (blocked, not
// finite, or bent back towards the camera body: see scene_ray).
bool emit(const SceneRay& ray, OpticsRay* out)
{
    if (!ray.passed)
        return false;
    out->origin_mm = ray.origin;
    out->dir = ray.dir;
    out->weight = 1;
    return true;
}

bool finish(Vec3 origin, Vec3 direction, OpticsRay* out) { return emit(scene_ray(origin, direction), out); }

// Under irradiance radiometry, weights a passing ray from sensor point s towards aperture point q
// (on a plane of normal n) by the cos^4 law (camera/radiometry.h); returns `passed`.
bool weigh(const PlenopticCamera& m, bool passed, Vec3 s, Vec3 q, Vec3 n, OpticsRay* out)
{
    if (passed && m.sensor.radiometry == Radiometry::Irradiance)
        out->weight *= irradiance_weight(m.sensor.irradiance_k_mm2, m.sensor.angular_exponent, s, q, n);
    return passed;
}

// The whole camera for one sensor point and one aperture sample (lens_u, lens_v); with `aim`, the
// sample is drawn from the part of the microlens's cell where light from p can pass (camera/aim.h)
// and the ray weighted by that part's share.
// (A template, so that the uniform path compiles as it did before aiming: no cost where nothing aims.)
template <bool aim>
bool trace_sensor_point_as(const PlenopticCamera& m, Vec3 p, const LensIndex* forced, double lens_u, double lens_v,
                           bool check_apertures, OpticsRay* out)
{
    if (m.array.grid == GridType::None && m.pupil_bounds && check_apertures) {
        // A real lens: towards a point of the region of the exit pupil's plane where light from p
        // can pass, weighted by that region's area, or by the lit part's when the model has a
        // lit-area table (see OpticsRay::weight). Chief rays (no
        // aperture check) aim at the exit pupil's centre, below.
        const PupilDisc disc = m.pupil_bounds->disc_for(p);
        if (!(disc.radius > 0))
            return false;
        const Vec2 d = concentric_disc(lens_u, lens_v);
        const Vec3 on_pupil{disc.centre.x + disc.radius * d.x, disc.centre.y + disc.radius * d.y, disc.centre.z};
        if (!emit(m.lens->to_scene(p, on_pupil - p, true), out))
            return false;
        if (m.lit_area) {
            out->weight = m.lit_area->at(p);  // the table holds the irradiance weighting too
            return true;
        }
        const double ratio = disc.radius / m.lens->exit_pupil_radius();
        out->weight = ratio * ratio;
        return weigh(m, true, p, on_pupil, Vec3{0, 0, 1}, out);
    }
    if (m.array.grid == GridType::None) {
        // The sensor point towards a point of the exit pupil, through the lens.
        const Vec3 on_pupil = m.lens->exit_pupil_point(lens_u, lens_v);
        return weigh(m, emit(m.lens->to_scene(p, on_pupil - p, false), out), p, on_pupil, Vec3{0, 0, 1}, out);
    }

    LensIndex lens;
    if (forced) {
        lens = *forced;
    } else {
        Vec2 q;
        if (!project_to_array(m, p, &q))
            return false;
        lens = m.array.nearest(q.x, q.y);
    }

    if (m.lens && !m.lens->forms_image()) {
        // A pinhole main lens at the origin: the one ray from p through the microlens that passes it
        // (none through a pinhole microlens: refused at parse time).
        const Vec3 pinhole{0, 0, 0};
        const ArrayRay ray = m.array.microlens->ray_through(m.array, p, lens, pinhole, check_apertures);
        return ray.passed && finish(ray.origin, ray.direction, out);
    }

    // Where the ray leaves the array, and its direction after the microlens (optics frame).
    double aimed = 1;
    const ArrayRay ray = aim ? aimed_cell_ray(m, p, lens, lens_u, lens_v, &aimed)
                             : m.array.microlens->sample_ray(m.array, p, lens, lens_u, lens_v);
    if (!ray.passed)
        return false;  // the sensor point is not behind the array
    const Vec3& leave = ray.origin;
    const Vec3& direction = ray.direction;

    if (!m.lens)
        return weigh(m, finish(leave, direction, out), p, ray.sampled, m.array.pose.normal, out);

    // A real lens: a ray that crosses the exit pupil's plane outside the pupil-bounds disc of the
    // point where its line crosses the array's plane cannot pass the lens (PupilBounds holds every
    // point through which light from that point passes; a ray leaving a tilted array or a lens off
    // the plane is tested from where its line meets it), so it is blocked without the
    // surface-by-surface trace: most of the rays at the rims of microimages and their vignetting
    // probes.
    if (check_apertures && m.pupil_bounds && !m.pupil_bounds->may_pass(leave, direction))
        return false;
    // On through the main lens (a ray that misses its apertures carries no light).
    const bool passed = weigh(m, emit(m.lens->to_scene(leave, direction, check_apertures), out), p, ray.sampled,
                              m.array.pose.normal, out);
    out->weight *= aimed;
    return passed;
}

bool trace_sensor_point(const PlenopticCamera& m, Vec3 p, const LensIndex* forced, double lens_u, double lens_v,
                        bool check_apertures, OpticsRay* out)
{
    return trace_sensor_point_as<false>(m, p, forced, lens_u, lens_v, check_apertures, out);
}

// Whether light through a lens can reach some point of the pixel centred at p, split into what
// depends on the lens alone (kept per thread for the lenses about the pixels being traced) and p:
// the lens reaches the pixel iff |(a - k p)_xy| <= radius (always when `always`).
struct LensReach {
    double ax = 0, ay = 0, k = 0, radius = 0;
    bool always = true;

    bool reaches(Vec3 p) const
    {
        if (always)
            return true;
        const double x = ax - k * p.x, y = ay - k * p.y;
        return x * x + y * y <= radius * radius;
    }
};

// With k = D/d measured at the lens: the chief ray p -> c meets the main-lens plane at
// m0 = c (1 + k) - p k (exact, tilted or not); a ray from sensor point p' through cell point h
// arrives at m0 + (h - c) g - (p' - p) k with g = 1 + k - D/f for an array parallel to the sensor,
// so the lens reaches the pixel iff that region meets the aperture disc. Conservative: circumradius
// for the cell, half the pixel diagonal for the pixel; for a slightly tilted array the spread terms
// get a margin that grows with the tilt (validated against brute force in the unit tests). The
// radius's factor 1 + 1e-9 covers the rounding of a - k p (|a|, |k p| of metres at most against
// radii of millimetres).
// Refracting lenses have no first-order bound: their light lands within the traced reach
// (Overlap::reach_mm) of the lens's microimage centre (the lens centre seen from the exit pupil's
// centre; for lenses that tilt, the largest of the tilted centre lens's: traced_reach_mm). Not
// pruned (always) without that reach, or where the array is tilted.
LensReach refracting_lens_reach(const PlenopticCamera& m, LensIndex lens)
{
    LensReach r;
    if (!(m.overlap.reach_mm > 0) || m.array.pose.tilted)
        return r;
    const Vec3 c = lens_centre_mm(m, lens);
    const Vec3 e = m.lens->exit_pupil_centre();
    const Vec3 centre = e + ((m.sensor.z_mm - e.z) / (c.z - e.z)) * (c - e);
    const double pixel = 0.5 * std::hypot(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1]);
    r.always = false;
    r.ax = centre.x;
    r.ay = centre.y;
    r.k = 1;
    r.radius = (m.overlap.reach_mm + pixel) * (1 + 1e-9);
    return r;
}

LensReach lens_reach(const PlenopticCamera& m, LensIndex lens)
{
    LensReach r;
    if (!m.lens)
        return r;
    const LensFrame frame = m.array.frame(lens);
    const Vec3 c = m.array.to_optics(frame.centre);
    const Vec3 e = m.lens->exit_pupil_centre();
    const double main_distance = e.z - c.z;
    const double array_distance = c.z - m.sensor.z_mm;
    if (!(main_distance > 0) || !(array_distance > 0))
        return r;
    const double k = main_distance / array_distance;
    double spread = 0.5 * std::hypot(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1]) * k;
    if (m.array.microlens->forms_image()) {
        if (!m.array.microlens->first_order_exact())
            return refracting_lens_reach(m, lens);
        double blur = std::fabs(1 + k - main_distance / frame.focal_mm);
        if (m.array.fill_factor < 1 && !m.array.mask)
            blur = std::max(blur, 1 + k);  // light through a clear gap is not bent
        spread += m.array.cell_circumradius_mm * blur;
    }
    if (m.array.pose.tilted)
        spread *= 1.25 + 4 * m.array.pose.tilt_sine;
    if (frame.tilted) {
        // This lens's own tilt, with the margin of a tilted array (validated by brute force).
        spread *= 1.25 + 4 * std::sin(m.array.errors->at(lens).tilt_deg * (kPi / 180));
    }
    // A real lens: the region where light from the lens centre passes its apertures.
    const PupilDisc disc = m.pupil_bounds ? m.pupil_bounds->disc_for(c) : PupilDisc{Vec3{0, 0, e.z}, m.lens->exit_pupil_radius()};
    r.always = false;
    r.ax = (c.x - e.x) * (1 + k) + e.x * k - disc.centre.x;
    r.ay = (c.y - e.y) * (1 + k) + e.y * k - disc.centre.y;
    r.k = k;
    r.radius = (disc.radius + spread) * (1 + 1e-9);
    return r;
}

// The reach tests of the lenses about the pixels a thread traces: a 32 x 32 tile of the lattice,
// slot (k mod 32, l mod 32), so that the lenses about one pixel (at most 17 x 17) never share a
// slot. A new camera (camera/camera_key.h) starts a new generation, which empties every slot.
struct ReachCache {
    static const int kSide = 32;
    struct Slot {
        std::uint64_t generation = 0;
        LensIndex lens{0, 0};
        LensReach reach;
    };
    CameraKey key;
    std::uint64_t generation = 0;
    Slot slots[kSide * kSide];

    const LensReach& of(const PlenopticCamera& m, LensIndex lens)
    {
        Slot& slot = slots[std::size_t(std::uint64_t(lens.k) & (kSide - 1)) +
                           kSide * std::size_t(std::uint64_t(lens.l) & (kSide - 1))];
        if (!(slot.generation == generation && slot.lens == lens)) {
            slot.reach = lens_reach(m, lens);
            slot.lens = lens;
            slot.generation = generation;
        }
        return slot.reach;
    }
};

ReachCache& reach_cache(const PlenopticCamera& m)
{
    thread_local ReachCache cache;
    if (cache.generation == 0 || !key_is(cache.key, m)) {
        cache.key = key_of(m);
        ++cache.generation;
    }
    return cache;
}

} // namespace

Vec3 Sensor::point(double pu, double pv) const
{
    const int W = film.width, H = film.height;
    return Vec3{-(pu - 0.5 * W) * pixel_size_mm[0] + offset_mm[0], (pv - 0.5 * H) * pixel_size_mm[1] + offset_mm[1],
                z_mm};
}

PixelPoint Sensor::to_pixel(double x_mm, double y_mm) const
{
    const int W = film.width, H = film.height;
    const double u = 0.5 * W - 0.5 - (x_mm - offset_mm[0]) / pixel_size_mm[0];
    const double v = 0.5 * H - 0.5 + (y_mm - offset_mm[1]) / pixel_size_mm[1];
    return PixelPoint{u, v, u >= -0.5 && u < W - 0.5 && v >= -0.5 && v < H - 0.5};
}

Vec2 Sensor::principal_point_px() const
{
    const PixelPoint p = to_pixel(0, 0);
    return Vec2{p.u, p.v};
}

Vec3 lens_centre_mm(const PlenopticCamera& m, LensIndex lens) { return m.array.centre_mm(lens); }

OwnLens own_lens(const PlenopticCamera& m, Vec3 p)
{
    Vec2 q;
    if (!project_to_array(m, p, &q))
        return OwnLens{LensIndex{0, 0}, false};
    return OwnLens{m.array.nearest(q.x, q.y), true};
}

namespace {

// The sample's own pixel point and cell point (inline in both callers: the uniform path costs what
// it did before aiming).
inline OpticsRay uniform_ray(const PlenopticCamera& m, int i, int j, const CameraSample& sample, const LensIndex* lens)
{
    const Vec3 p = m.sensor.point(i + sample.pixel_u, j + sample.pixel_v);
    OpticsRay ray;
    ray.passed = trace_sensor_point(m, p, lens, sample.lens_u, sample.lens_v, true, &ray);
    return ray;
}

} // namespace

OpticsRay generate_ray_unaimed(const PlenopticCamera& m, int i, int j, const CameraSample& sample, const LensIndex* lens)
{
    return uniform_ray(m, i, j, sample, lens);
}

OpticsRay generate_ray(const PlenopticCamera& m, int i, int j, const CameraSample& sample, const LensIndex* lens)
{
    if (!m.sampling.aim)
        return uniform_ray(m, i, j, sample, lens);
    // The pixel's point where light through its lens can land, then the cell's part where light from
    // there can pass; the weights of both choices multiply.
    OpticsRay ray;
    const PixelAim at = aim_pixel(m, i, j, sample.pixel_u, sample.pixel_v, lens);
    if (!at.passed) {
        ray.passed = false;
        return ray;
    }
    const Vec3 p = m.sensor.point(at.pu, at.pv);
    ray.passed = trace_sensor_point_as<true>(m, p, at.lens_forced ? &at.lens : lens, sample.lens_u, sample.lens_v, true, &ray);
    if (ray.passed)
        ray.weight *= at.weight;
    return ray;
}

int overlap_lenses(const PlenopticCamera& m, int i, int j, LensIndex* out, int capacity)
{
    if (capacity < 1 || m.array.grid == GridType::None)
        return 0;
    const Vec3 p = m.sensor.point(i + 0.5, j + 0.5);
    const OwnLens lookup = own_lens(m, p);
    if (!lookup.found)
        return 0;
    const LensIndex own = lookup.lens;
    out[0] = own;
    int count = 1;
    if (!m.overlap.modelled)
        return count;
    const int rings = m.overlap.rings;
    ReachCache* reach = m.array.pose.tilt_sine <= kMaxPrunedTiltSine ? &reach_cache(m) : nullptr;
    const std::int64_t own_skew = skew_k(m.array.grid, own);
    const bool hexagonal = m.array.grid == GridType::Hexagonal;
    for (int dl = -rings; dl <= rings; ++dl) {
        // Hexagonal ring distance in skew indices: max(|dk|, |dl|, |dk + dl|), so |dk + dl| <= rings.
        const int first = hexagonal ? std::max(-rings, -rings - dl) : -rings;
        const int last = hexagonal ? std::min(rings, rings - dl) : rings;
        const std::int64_t l = own.l + dl;
        const LensIndex row = from_skew(m.array.grid, own_skew, l);  // the row's lens at dk = 0
        for (int dk = first; dk <= last; ++dk) {
            if (dk == 0 && dl == 0)
                continue;
            const LensIndex lens{row.k + dk, l};
            if (reach && !reach->of(m, lens).reaches(p))
                continue;
            if (count >= capacity)
                return count;
            out[count++] = lens;
        }
    }
    return count;
}

OpticsRay chief_ray_through(const PlenopticCamera& m, double pu, double pv, const LensIndex* lens)
{
    OpticsRay ray;
    ray.passed = trace_sensor_point(m, m.sensor.point(pu, pv), lens, 0.5, 0.5, false, &ray);
    return ray;
}

OpticsRay chief_ray(const PlenopticCamera& m, int i, int j)
{
    OpticsRay ray = chief_ray_through(m, i + 0.5, j + 0.5);
    if (ray.passed)
        return ray;
    const Vec3 p = m.sensor.point(i + 0.5, j + 0.5);
    const Vec3 e = m.lens ? m.lens->exit_pupil_centre() : Vec3{0, 0, 0};
    ray.passed = finish(e, e - p, &ray) || finish(e, Vec3{0, 0, 1}, &ray);
    return ray;
}

OpticsRay PlenopticCamera::generate_ray(int i, int j, const CameraSample& sample) const
{
    return plenoptic::generate_ray(*this, i, j, sample);
}

OpticsRay PlenopticCamera::chief_ray(int i, int j) const
{
    return plenoptic::chief_ray(*this, i, j);
}

} // namespace plenoptic
