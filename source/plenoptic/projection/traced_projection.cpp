// SPDX-License-Identifier: AGPL-3.0-or-later
// Forward projection through a traced main lens: the point's light sampled ray by ray.

#include "plenoptic/projection/traced_projection.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "plenoptic/projection/projection_internal.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/camera/rays_internal.h"

namespace plenoptic {

namespace {

using detail::add_point_hit;
using detail::delivered_point;
using detail::sensor_hit_through_lens;

// A square of the window's plane: centre (x, y), half side.
struct Square {
    double x, y, half;
};

struct Box2 {
    bool valid;
    double x0, x1, y0, y1;
    void include(double x, double y)
    {
        if (!valid) {
            *this = Box2{true, x, x, y, y};
            return;
        }
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
        y0 = std::min(y0, y);
        y1 = std::max(y1, y);
    }
};

// The ray from the point through window point (x, y) at the window's z, traced to the image side.
ImageRay trace_through(const PlenopticCamera& m, Vec3 point, double window_z, double x, double y, bool check_apertures)
{
    return m.lens->to_image(point, Vec3{x, y, window_z} - point, check_apertures);
}

// Where a ray leaving the lens meets the array plane (optics frame); false if it does not.
bool array_hit(const PlenopticCamera& m, const ImageRay& ray, Vec3* h)
{
    const double along = dot(m.array.pose.normal, ray.dir);
    const double t = dot(m.array.pose.normal, m.array.pose.centre_mm - ray.origin) / along;
    if (!(t > 0) || !std::isfinite(t))
        return false;
    *h = ray.origin + t * ray.dir;
    return is_finite(*h);
}

// The passing part of a coarse grid over a disc of the window's plane: the box of its window
// points and the box of where those rays meet the array (local coordinates; not valid without an
// array).
struct Coarse {
    Box2 window, array;
    double step;
};

Coarse coarse_pass(const PlenopticCamera& m, Vec3 point, double window_z, Square disc, int n)
{
    Coarse out{Box2{false, 0, 0, 0, 0}, Box2{false, 0, 0, 0, 0}, 2 * disc.half / n};
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const double dx = (i + 0.5) * out.step - disc.half, dy = (j + 0.5) * out.step - disc.half;
            if (dx * dx + dy * dy > disc.half * disc.half)
                continue;
            const ImageRay ray = trace_through(m, point, window_z, disc.x + dx, disc.y + dy, true);
            if (!ray.passed)
                continue;
            out.window.include(disc.x + dx, disc.y + dy);
            Vec3 h;
            if (m.array.grid != GridType::None && array_hit(m, ray, &h)) {
                const Vec3 local = m.array.to_local(h);
                out.array.include(local.x, local.y);
            }
        }
    }
    return out;
}

// Per lens: the delivered light's weight and weighted sensor position (thin microlenses), or the
// grid ray that met the array nearest the lens centre (pinholes).
struct LensLight {
    double weight, sx, sy;
    double nearest2;
    double wx, wy;  // its window point
};

typedef std::pair<std::int64_t, std::int64_t> RowKey;  // (l, k): row order

// Newton's method for the window point whose ray meets the array at the centre of `lens`
// (apertures ignored while iterating, so that a lens near the edge of the light converges).
bool ray_through_centre(const PlenopticCamera& m, Vec3 point, double window_z, LensIndex lens, double step, double* x, double* y)
{
    const Vec2 c = m.array.centre_local(lens);
    auto miss = [&](double px, double py, Vec2* out) {
        const ImageRay ray = trace_through(m, point, window_z, px, py, false);
        Vec3 h;
        if (!ray.passed || !array_hit(m, ray, &h))
            return false;
        const Vec3 local = m.array.to_local(h);
        *out = Vec2{local.x - c.x, local.y - c.y};
        return true;
    };
    const double tolerance = 1e-10 * m.array.pitch_mm;
    const double delta = 1e-4 * step;
    for (int iteration = 0; iteration < 40; ++iteration) {
        Vec2 f;
        if (!miss(*x, *y, &f))
            return false;
        if (length(f) <= tolerance)
            return true;
        Vec2 fx0, fx1, fy0, fy1;
        if (!miss(*x - delta, *y, &fx0) || !miss(*x + delta, *y, &fx1) || !miss(*x, *y - delta, &fy0) ||
            !miss(*x, *y + delta, &fy1))
            return false;
        const double a = (fx1.x - fx0.x) / (2 * delta), b = (fy1.x - fy0.x) / (2 * delta);
        const double cc = (fx1.y - fx0.y) / (2 * delta), d = (fy1.y - fy0.y) / (2 * delta);
        const double det = a * d - b * cc;
        const double scale = std::fabs(a) + std::fabs(b) + std::fabs(cc) + std::fabs(d);
        if (!(std::fabs(det) > 1e-12 * scale * scale) || !std::isfinite(det))
            return false;  // the point is focused on the array: every ray meets it at one place
        double sx = (d * f.x - b * f.y) / det, sy = (-cc * f.x + a * f.y) / det;
        const double most = 4 * step;  // a Newton step never jumps further than a few grid steps
        const double len = std::hypot(sx, sy);
        if (len > most) {
            sx *= most / len;
            sy *= most / len;
        }
        *x -= sx;
        *y -= sy;
    }
    return false;
}

// One ray of the point's light: what became of it.
struct Ray {
    enum Kind { Blocked, Undelivered, Delivered } kind;
    RowKey lens;       // Delivered (and, for pinholes, any ray meeting the array): its lens
    double weight;     // solid angle per unit of window area (Blocked: 0)
    double sx, sy;     // Delivered: where it meets the sensor
    double wx, wy;     // its window point
    double nearest2;   // squared distance from its lens centre on the array (-1: met no lens)
};

// The ray from the point through window point (wx, wy): traced through the main lens, to the
// array, through its microlens to the sensor; Delivered when the renderer gives it to the picture
// (delivered_point); without an array, Delivered when it reaches the sensor plane.
Ray sample(const PlenopticCamera& m, Vec3 point, double window_z, double wx, double wy)
{
    Ray out{Ray::Blocked, RowKey(0, 0), 0, 0, 0, wx, wy, -1};
    const Vec3 to_window = Vec3{wx, wy, window_z} - point;
    const ImageRay ray = m.lens->to_image(point, to_window, true);
    if (!ray.passed)
        return out;
    // Solid angle of a window cell seen from the point: dA cos(theta) / r^2, cos(theta) = gap / r
    // (the gap is common to every ray, dA the unit).
    const double r = length(to_window);
    out.weight = 1 / (r * r * r);
    out.kind = Ray::Undelivered;
    if (m.array.grid == GridType::None) {
        const double t = (m.sensor.z_mm - ray.origin.z) / ray.dir.z;
        if (t > 0 && std::isfinite(t)) {
            out.kind = Ray::Delivered;
            out.sx = ray.origin.x + t * ray.dir.x;
            out.sy = ray.origin.y + t * ray.dir.y;
        }
        return out;
    }
    Vec3 h;
    if (!array_hit(m, ray, &h))
        return out;
    const Vec3 local = m.array.to_local(h);
    const LensIndex lens = m.array.nearest(local.x, local.y);
    const Vec2 c = m.array.centre_local(lens);
    out.lens = RowKey(lens.l, lens.k);
    out.nearest2 = (local.x - c.x) * (local.x - c.x) + (local.y - c.y) * (local.y - c.y);
    Vec3 sensor;
    if (!m.array.microlens->forms_image() || !sensor_hit_through_lens(m, lens, h, ray.dir, &sensor) ||
        !delivered_point(m, lens, Vec2{sensor.x, sensor.y}))
        return out;
    out.kind = Ray::Delivered;
    out.sx = sensor.x;
    out.sy = sensor.y;
    return out;
}

// The integrals of the point's light: in all (every ray that passes the main lens) and per lens
// (the delivered light's weight and weighted sensor position), or, for pinholes, the ray that
// met the array nearest each lens centre.
struct Integrals {
    double total = 0;
    std::map<RowKey, LensLight> lenses;

    void add(const Ray& ray, double share)
    {
        if (ray.kind == Ray::Blocked)
            return;
        total += share * ray.weight;
        if (ray.kind != Ray::Delivered)
            return;
        LensLight& acc = lenses[ray.lens];
        acc.weight += share * ray.weight;
        acc.sx += share * ray.weight * ray.sx;
        acc.sy += share * ray.weight * ray.sy;
    }
    void nearest(const Ray& ray)
    {
        if (ray.nearest2 < 0)
            return;
        total += ray.weight;
        auto found = lenses.find(ray.lens);
        if (found == lenses.end() || ray.nearest2 < found->second.nearest2)
            lenses[ray.lens] = LensLight{0, 0, 0, ray.nearest2, ray.wx, ray.wy};
    }
};

} // namespace

TracedProjectionOptions default_traced_projection_options()
{
    TracedProjectionOptions options;
    options.cells_per_pitch = 32;
    options.subdivision = 8;
    options.min_grid = 128;
    options.max_grid = 1024;
    return options;
}

std::vector<PixelHit> forward_project_traced(const PlenopticCamera& m, Vec3 point,
                                             const TracedProjectionOptions& options)
{
    std::vector<PixelHit> hits;
    FrontWindow window;
    if (!m.lens || !is_finite(point) || !m.lens->front_window(&window) || !(window.radius > 0))
        return hits;
    const double gap = point.z - window.z;
    if (!(gap > 2 * window.sag) || !(gap > 0))
        return hits;

    // Every passing ray crosses the window's plane within this reach of the axis: it meets the
    // surface at most `sag` beyond the plane, at most radius from the axis.
    const double lateral = std::hypot(point.x, point.y);
    const double s = window.sag / gap;
    const double reach = 1.001 * (window.radius + lateral * s) / (1 - s);
    const int kCoarse = 96;
    Coarse coarse = coarse_pass(m, point, window.z, Square{0, 0, reach}, kCoarse);
    if (!coarse.window.valid) {
        // A stop much smaller than the window: look about the paraxial entrance pupil.
        const FrontWindow pupil = m.lens->entrance_pupil();
        const double pupil_z = pupil.z, pupil_radius = pupil.radius;
        if (!(point.z > pupil_z) || !(pupil_radius > 0))
            return hits;
        const double scale = gap / (point.z - pupil_z);
        const Vec2 aim{point.x * (1 - scale), point.y * (1 - scale)};  // the line point -> pupil centre
        coarse = coarse_pass(m, point, window.z, Square{aim.x, aim.y, 3 * pupil_radius * scale}, kCoarse);
        if (!coarse.window.valid)
            return hits;
    }

    // The fine grid: over the passing part, grown by a coarse step and a half, with about
    // cells_per_pitch cells across each lens cell the footprint on the array covers.
    const double grow = 1.5 * coarse.step;
    const double x0 = coarse.window.x0 - grow, x1 = coarse.window.x1 + grow;
    const double y0 = coarse.window.y0 - grow, y1 = coarse.window.y1 + grow;
    double lenses_across = 1;
    if (m.array.grid != GridType::None && coarse.array.valid)
        lenses_across += std::max(coarse.array.x1 - coarse.array.x0, coarse.array.y1 - coarse.array.y0) / m.array.pitch_mm;
    const double wanted = std::ceil(options.cells_per_pitch * lenses_across);
    const int n = int(std::min<double>(options.max_grid, std::max<double>(options.min_grid, wanted)));
    const double step_x = (x1 - x0) / n, step_y = (y1 - y0) / n;
    const int sub = std::max(1, options.subdivision);

    // The light is integrated cell by cell. The rays through a cell's four corners decide: all
    // of one kind (blocked; passed but not delivered; delivered through one lens), the cell is
    // integrated from its corners (trapezoidal rule); otherwise it straddles an edge of the
    // light (an aperture's shadow, a lens cell, the picture) and is integrated from sub x sub
    // rays through its parts. The cell's area is the unit of weight.
    Integrals light;
    auto node_row = [&](int j, std::vector<Ray>* row) {
        row->resize(n + 1);
        for (int i = 0; i <= n; ++i)
            (*row)[i] = sample(m, point, window.z, x0 + i * step_x, y0 + j * step_y);
    };
    // Pinholes pass light only at their centres: each needs only the ray nearest it.
    const bool pinholes = m.array.present() && !m.array.microlens->forms_image();
    std::vector<Ray> below, above;
    node_row(0, &below);
    for (int j = 0; j < n; ++j) {
        node_row(j + 1, &above);
        for (int i = 0; i < n; ++i) {
            const Ray* corner[4] = {&below[i], &below[i + 1], &above[i], &above[i + 1]};
            if (pinholes) {
                light.nearest(*corner[0]);  // pinholes need only the ray nearest each lens centre
                continue;
            }
            bool same = true;
            for (int c = 1; c < 4; ++c)
                same = same && corner[c]->kind == corner[0]->kind && corner[c]->lens == corner[0]->lens;
            if (same) {
                for (int c = 0; c < 4; ++c)
                    light.add(*corner[c], 0.25);
                continue;
            }
            for (int b = 0; b < sub; ++b)
                for (int a = 0; a < sub; ++a)
                    light.add(sample(m, point, window.z, x0 + (i + (a + 0.5) / sub) * step_x,
                                     y0 + (j + (b + 0.5) / sub) * step_y),
                              1.0 / (sub * sub));
        }
        if (pinholes)
            for (int i = 0; i < n; ++i)
                light.nearest(above[i]);
        below.swap(above);
    }
    const double total = light.total;
    if (!(total > 0))
        return hits;

    if (m.array.grid == GridType::None) {
        const LensLight& spot = light.lenses[RowKey(0, 0)];
        if (!(spot.weight > 0))
            return hits;
        const PixelPoint px = m.sensor.to_pixel(spot.sx / spot.weight, spot.sy / spot.weight);
        if (px.inside)
            hits.push_back(PixelHit{LensIndex{0, 0}, px.u, px.v, 1.0});
        return hits;
    }
    for (const auto& entry : light.lenses) {
        const LensIndex lens{entry.first.second, entry.first.first};
        const LensLight& acc = entry.second;
        if (pinholes) {
            double wx = acc.wx, wy = acc.wy;
            if (!ray_through_centre(m, point, window.z, lens, std::max(step_x, step_y), &wx, &wy))
                continue;
            const ImageRay ray = trace_through(m, point, window.z, wx, wy, true);
            Vec3 h, sensor;
            if (ray.passed && array_hit(m, ray, &h) && sensor_hit_through_lens(m, lens, h, ray.dir, &sensor))
                add_point_hit(m, lens, sensor, 1.0, &hits);
            continue;
        }
        if (!(acc.weight > 0))
            continue;
        const PixelPoint px = m.sensor.to_pixel(acc.sx / acc.weight, acc.sy / acc.weight);
        if (px.inside)
            hits.push_back(PixelHit{lens, px.u, px.v, std::min(1.0, acc.weight / total)});
    }
    return hits;
}

} // namespace plenoptic
