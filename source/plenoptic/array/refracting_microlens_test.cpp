// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the refracting microlenses against optics worked out here: the thick lens's focal
// length and back focal distance from the lensmaker's formula with thickness, and a tracer of this
// file's own (the sphere found from its centre, Snell's law in tangential form) for the marginal
// rays, total internal reflection and the cell's clear aperture.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "plenoptic/array/array_params.h"
#include "plenoptic/array/microlens_array.h"
#include "plenoptic/array/refracting_microlens.h"

namespace plenoptic {
namespace {

RefractingShape shape(bool curved_towards_scene, double R = 0.1, double n = 1.5, double t = 0.02, double T = 0.03)
{
    RefractingShape s;
    s.radius_mm = R;
    s.ior = n;
    s.cap_mm = t;
    s.substrate_mm = T;
    s.curved_towards_scene = curved_towards_scene;
    return s;
}

// The lensmaker's formula with thickness d for surfaces of radii R1, R2 (1/R2 = 0: flat), and
// the back focal distance f (1 - (n - 1) d / (n R1)) from the last surface.
double lensmaker_focal(double n, double inv_r1, double inv_r2, double d)
{
    return 1 / ((n - 1) * (inv_r1 - inv_r2 + (n - 1) * d * inv_r1 * inv_r2 / n));
}

// ---- this file's own tracer: spheres by their centre, Snell in tangential form ----

struct TestRay {
    Vec3 p, d;  // d unit
    bool ok;
};

// The cap's sphere: centre and which hemisphere is the cap (+1: the points above the centre).
struct Sphere {
    Vec3 centre;
    double radius;
    double side;
};

Sphere cap_sphere(const RefractingShape& s)
{
    const double L = s.cap_mm + s.substrate_mm;
    if (s.curved_towards_scene)
        return Sphere{Vec3{0, 0, L - s.radius_mm}, s.radius_mm, 1};
    return Sphere{Vec3{0, 0, s.radius_mm}, s.radius_mm, -1};
}

// The point of the cap hemisphere on the ray, the nearest ahead.
bool hit_sphere(const Sphere& sp, const TestRay& r, Vec3* q)
{
    const Vec3 o = r.p - sp.centre;
    const double b = dot(o, r.d), c = dot(o, o) - sp.radius * sp.radius;
    const double disc = b * b - c;
    if (disc < 0)
        return false;
    const double roots[2] = {-b - std::sqrt(disc), -b + std::sqrt(disc)};
    for (double t : roots) {
        const Vec3 x = r.p + t * r.d;
        if (t > 1e-12 && (x.z - sp.centre.z) * sp.side > 0) {
            *q = x;
            return true;
        }
    }
    return false;
}

// Snell: the tangential part of the direction scales by n1/n2, the normal part follows from unit length.
bool snell(Vec3 d, Vec3 normal, double n1, double n2, Vec3* out)
{
    Vec3 nn = normalized(normal);
    if (dot(d, nn) < 0)
        nn = -nn;  // along the travel
    const double along = dot(d, nn);
    const Vec3 tangential = (n1 / n2) * (d - along * nn);
    const double t2 = dot(tangential, tangential);
    if (t2 > 1)
        return false;
    *out = tangential + std::sqrt(1 - t2) * nn;
    return true;
}

// Light from the scene travelling along `travel` (down), on the line through h at z = 0: the ray below the lens.
TestRay test_trace_down(const RefractingShape& s, Vec3 h, Vec3 travel)
{
    const Sphere sp = cap_sphere(s);
    const double L = s.cap_mm + s.substrate_mm, n = s.ior;
    const Vec3 d = normalized(travel);
    if (s.curved_towards_scene) {
        Vec3 q, inside, out;
        const TestRay from_above{h - (10 * L / -d.z) * d, d, true};
        if (!hit_sphere(sp, from_above, &q) || !snell(d, q - sp.centre, 1, n, &inside))
            return TestRay{h, d, false};
        const Vec3 back = q + (q.z / -inside.z) * inside;
        if (!snell(inside, Vec3{0, 0, 1}, n, 1, &out))
            return TestRay{back, inside, false};
        return TestRay{back, out, true};
    }
    const Vec3 front = h + ((L - h.z) / d.z) * d;
    Vec3 inside, q, out;
    snell(d, Vec3{0, 0, 1}, 1, n, &inside);
    if (!hit_sphere(sp, TestRay{front, inside, true}, &q) || !snell(inside, q - sp.centre, n, 1, &out))
        return TestRay{front, inside, false};
    return TestRay{q, out, true};
}

// Where a ray crosses the axis (its z), from its x-z trace.
double axis_crossing_z(const Vec3& p, const Vec3& d) { return p.z - p.x / d.x * d.z; }

// ---- tests ----

TEST(RefractingMicrolens, ParaxialFocusIsTheThickLensFromTheLensmakersFormula)
{
    for (bool scene_side : {true, false}) {
        const RefractingShape s = shape(scene_side, 0.12, 1.56, 0.015, 0.04);
        const double L = s.cap_mm + s.substrate_mm;
        // Curved side first (towards the scene): R1 = R, R2 flat; flat side first: R1 flat, R2 = -R.
        const double f = scene_side ? lensmaker_focal(s.ior, 1 / s.radius_mm, 0, L)
                                    : lensmaker_focal(s.ior, 0, -1 / s.radius_mm, L);
        const double bfd = scene_side ? f * (1 - (s.ior - 1) * L / (s.ior * s.radius_mm)) : f;
        EXPECT_NEAR(s.focal_length_mm(), f, 1e-12 * f);
        const double h = 1e-5;
        const RefractingPath path = trace_to_sensor(s, Vec3{h, 0, 0}, Vec3{0, 0, 1});
        ASSERT_TRUE(path.passed);
        const Vec3 out = -path.sensor_side_dir;  // travelling down
        // EFL: the incoming height over the outgoing slope; BFD: from the last surface (the flat back
        // at z = 0, or the cap's vertex at z = 0) to the axis crossing.
        EXPECT_NEAR(h / (-out.x / -out.z), f, 1e-7 * f) << scene_side;
        EXPECT_NEAR(-axis_crossing_z(path.sensor_face, out), bfd, 1e-7 * f) << scene_side;
        // The principal planes: rear at the focus + f, front from the reverse trace.
        EXPECT_NEAR(axis_crossing_z(path.sensor_face, out) + f, s.rear_principal_z(), 1e-7 * f);
        const RefractingPath up = trace_to_scene(s, Vec3{h, 0, 0}, Vec3{0, 0, 1});
        ASSERT_TRUE(up.passed);
        EXPECT_NEAR(axis_crossing_z(up.scene_face, up.scene_side_dir) - f, s.front_principal_z(), 1e-7 * f);
    }
}

TEST(RefractingMicrolens, MarginalRaysFollowAnIndependentTracer)
{
    for (bool scene_side : {true, false}) {
        const RefractingShape s = shape(scene_side, 0.1, 1.5, 0.02, 0.03);
        const double paraxial = [&] {
            const RefractingPath p = trace_to_sensor(s, Vec3{1e-6, 0, 0}, Vec3{0, 0, 1});
            return axis_crossing_z(p.sensor_face, -p.sensor_side_dir);
        }();
        double previous_lsa = 0;
        for (double h : {0.01, 0.02, 0.03, 0.045}) {
            const TestRay mine = test_trace_down(s, Vec3{h, 0, 0}, Vec3{0, 0, -1});
            const RefractingPath path = trace_to_sensor(s, Vec3{h, 0, 0}, Vec3{0, 0, 1});
            ASSERT_TRUE(mine.ok && path.passed) << h;
            EXPECT_NEAR(path.sensor_face.x, mine.p.x, 1e-12);
            EXPECT_NEAR(path.sensor_face.z, mine.p.z, 1e-12);
            const double z_mine = axis_crossing_z(mine.p, mine.d);
            const double z_lib = axis_crossing_z(path.sensor_face, -path.sensor_side_dir);
            EXPECT_NEAR(z_lib, z_mine, 1e-10) << "height " << h << (scene_side ? " caps to the scene" : " caps to the sensor");
            // Under-corrected spherical aberration: the marginal focus nearer the lens, more so with height.
            const double lsa = z_mine - paraxial;
            EXPECT_GT(lsa, previous_lsa) << h;
            previous_lsa = lsa;
        }
        EXPECT_GT(previous_lsa, 1e-3) << "a visible aberration at the rim";
        // An oblique ray too (a general direction).
        const Vec3 travel = normalized(Vec3{0.2, -0.15, -1});
        const TestRay mine = test_trace_down(s, Vec3{0.01, 0.02, 0}, travel);
        const RefractingPath path = trace_to_sensor(s, Vec3{0.01, 0.02, 0}, -travel);
        ASSERT_TRUE(mine.ok && path.passed);
        EXPECT_NEAR(length(path.sensor_face - mine.p), 0, 1e-12);
        EXPECT_NEAR(length(-path.sensor_side_dir - mine.d), 0, 1e-12);
    }
}

TEST(RefractingMicrolens, TotalInternalReflectionBlocks)
{
    // Caps towards the sensor: light leaves through the flat front; caps towards the scene: through the cap.
    for (bool scene_side : {true, false}) {
        const RefractingShape s = shape(scene_side, 0.1, 1.8, 0.02, 0.03);
        int reflected = 0, passed = 0;
        for (int i = 0; i < 200; ++i) {
            const double angle = i * (89.0 / 200) * kPi / 180;
            const Vec3 travel{std::sin(angle), 0, -std::cos(angle)};
            const Vec3 h{-0.03, 0.01, 0};
            const TestRay mine = test_trace_down(s, h, travel);
            const RefractingPath path = trace_to_sensor(s, h, -travel);
            // Both trace the same surfaces; a failure of the test's tracer is a miss or a reflection.
            EXPECT_EQ(path.passed, mine.ok) << angle;
            if (!mine.ok)
                ++reflected;
            else
                ++passed;
        }
        EXPECT_GT(reflected, 5);
        EXPECT_GT(passed, 5);
    }
    // The reflection at the cap, written out: a ray inside the glass meeting the cap beyond the critical angle.
    const RefractingShape s = shape(true, 0.1, 1.8, 0.02, 0.03);
    const double critical = std::asin(1 / s.ior);
    // Inside at angle a to the axis, from the flat back at x0 < 0 towards +x; in air the ray enters at
    // asin(n sin a). At the cap point the normal tilts by asin(x / R) towards +x.
    int checked = 0;
    for (double a_deg = 1; a_deg < 33; a_deg += 1) {
        const double a = a_deg * kPi / 180;
        const Vec3 inside{std::sin(a), 0, std::cos(a)};
        const Vec3 air{s.ior * std::sin(a), 0, std::sqrt(1 - s.ior * s.ior * std::sin(a) * std::sin(a))};
        const Vec3 h0{0.01, 0, 0};
        Vec3 q;
        const Sphere sp = cap_sphere(s);
        ASSERT_TRUE(hit_sphere(sp, TestRay{h0, inside, true}, &q));
        const double incidence = std::acos(dot(inside, normalized(q - sp.centre)));
        const RefractingPath path = trace_to_scene(s, h0, air);
        EXPECT_EQ(path.passed, incidence < critical) << a_deg;
        ++checked;
    }
    EXPECT_GT(checked, 0);
}

MicrolensArray refracting_array(bool scene_side, double pitch = 0.1, double substrate = 0.03)
{
    ArrayParams a;
    a.given = true;
    a.grid = GridType::Hexagonal;
    a.has_pitch = true;
    a.pitch_mm = pitch;
    a.has_lens = true;
    a.lens = MicrolensType::Refracting;
    a.refracting = shape(scene_side, 0.08, 1.5, 0.025, substrate);
    a.has_distance = true;
    a.distance_mm = 0.2;
    return make_microlens_array(a, -50);
}

// Inside the hexagonal cell of pitch p (horizontal rows: neighbours at 0, 60, 120 degrees, a
// corner at the top) centred at the origin.
bool in_hexagon(double x, double y, double p)
{
    const double inradius = p / 2;
    for (int k = 0; k < 3; ++k) {
        const double angle = k * kPi / 3;  // normals of the cell's sides: towards the neighbours
        if (std::fabs(x * std::cos(angle) + y * std::sin(angle)) > inradius)
            return false;
    }
    return true;
}

// This file's trace of the line from sensor point p through cell point h0 of `lens` (optics frame,
// an unrotated ideal array): with `baffles` the path must cross both faces inside the lens's own
// cell; without, the glass's surface is each lens's cap inside that lens's cell (the caps meet at
// the cells' borders), and the path leaves through the first of them it meets. Returns whether it
// passes, where it leaves the glass towards the scene and its direction there; *crossed: whether
// it crossed a face outside its own cell.
bool test_trace_array(const MicrolensArray& array, LensIndex lens, Vec3 p, Vec3 h0, bool baffles, Vec3* exit_point,
                      Vec3* out, bool* crossed)
{
    const RefractingShape& s = *refracting_shape(*array.microlens);
    const double L = s.cap_mm + s.substrate_mm, n = s.ior;
    const Vec3 c = array.centre_mm(lens);
    const Vec3 d = normalized(h0 - p);
    // The first point ahead on the line where it meets some lens's cap inside that lens's cell.
    auto first_cap = [&](Vec3 from, Vec3 dir, double after, Vec3* q, Vec3* centre) {
        double best = INFINITY;
        for (int dl = -6; dl <= 6; ++dl) {
            for (int dk = -6; dk <= 6; ++dk) {
                const Vec3 cj = array.centre_mm(LensIndex{lens.k + dk, lens.l + dl});
                Sphere sp = cap_sphere(s);
                sp.centre = sp.centre + cj;
                Vec3 x;
                const Vec3 o = from - sp.centre;
                const double b = dot(o, dir), cc = dot(o, o) - sp.radius * sp.radius, disc = b * b - cc;
                if (disc < 0)
                    continue;
                for (double t : {-b - std::sqrt(disc), -b + std::sqrt(disc)}) {
                    x = from + t * dir;
                    if (t > after && t < best && (x.z - sp.centre.z) * sp.side > 0 &&
                        in_hexagon(x.x - cj.x, x.y - cj.y, array.pitch_mm)) {
                        best = t;
                        *q = x;
                        *centre = sp.centre;
                    }
                }
            }
        }
        return best < INFINITY;
    };
    Vec3 q, centre, inside;
    if (s.curved_towards_scene) {
        if (!snell(d, Vec3{0, 0, 1}, 1, n, &inside) || !first_cap(h0, inside, 1e-12, &q, &centre))
            return false;
        *crossed = !in_hexagon(q.x - c.x, q.y - c.y, array.pitch_mm);
        *exit_point = q;
        return !(baffles && *crossed) && snell(inside, q - centre, n, 1, out);
    }
    if (!first_cap(h0 - 1.0 * d, d, 0, &q, &centre) || !snell(d, q - centre, 1, n, &inside))
        return false;
    const Vec3 front = q + ((c.z + L - q.z) / inside.z) * inside;
    Vec3 again, again_centre;
    if (first_cap(q, inside, 1e-12, &again, &again_centre) && again.z < front.z)
        return false;  // back out through a cap: not towards the scene
    *crossed = !in_hexagon(q.x - c.x, q.y - c.y, array.pitch_mm) || !in_hexagon(front.x - c.x, front.y - c.y, array.pitch_mm);
    *exit_point = front;
    return !(baffles && *crossed) && snell(inside, Vec3{0, 0, 1}, n, 1, out);
}

TEST(RefractingMicrolens, RaysLeavingTheCellGoOnInTheNeighboursUnlessBaffled)
{
    for (bool scene_side : {true, false}) {
        for (bool baffles : {false, true}) {
            // A thick substrate (0.15 mm under a 0.1 mm pitch): paths cross cells both ways round.
            MicrolensArray array = refracting_array(scene_side, 0.1, 0.15);
            array.baffles = baffles;
            const LensIndex lens{2, 1};
            const Vec3 c = array.centre_mm(lens);
            std::mt19937 rng(7);
            std::uniform_real_distribution<double> uni(0, 1);
            int crossed_passed = 0, crossed_blocked = 0, passed = 0;
            for (int i = 0; i < 4000; ++i) {
                // Sensor points far off the lens's axis: steep rays that cross into the neighbours' cells.
                const Vec3 p{c.x + (uni(rng) - 0.5) * 0.6, c.y + (uni(rng) - 0.5) * 0.6, c.z - array.distance_mm};
                const double u = uni(rng), v = uni(rng);
                const ArrayRay ray = array.microlens->sample_ray(array, p, lens, u, v);
                const Vec2 off = array.cell_point(u, v);
                const Vec3 h0{c.x + off.x, c.y + off.y, c.z};
                Vec3 exit_point, out;
                bool crossed = false;
                const bool ok = test_trace_array(array, lens, p, h0, baffles, &exit_point, &out, &crossed);
                EXPECT_EQ(ray.passed, ok) << i << (scene_side ? " scene" : " sensor") << (baffles ? " baffles" : "");
                if (crossed)
                    ++(ray.passed ? crossed_passed : crossed_blocked);
                if (ray.passed && ok) {
                    ++passed;
                    // The ray leaves along the test's direction, on the test's line.
                    EXPECT_NEAR(length(normalized(ray.direction) - out), 0, 1e-9) << i;
                    EXPECT_NEAR(length(cross(exit_point - ray.origin, normalized(ray.direction))), 0, 1e-10) << i;
                    EXPECT_NEAR(length(ray.sampled - h0), 0, 1e-12);
                }
            }
            // Without baffles light crosses into the neighbours' glass and passes; with them none.
            if (baffles) {
                EXPECT_EQ(crossed_passed, 0);
                EXPECT_GT(crossed_blocked, 50);
            } else {
                EXPECT_GT(crossed_passed, 50);
            }
            EXPECT_GT(passed, 200);
        }
    }
}

TEST(RefractingMicrolens, TowardsSensorInvertsSampleRay)
{
    for (bool scene_side : {true, false}) {
        const MicrolensArray array = refracting_array(scene_side);
        const LensIndex lens{-1, 3};
        const Vec3 c = array.centre_mm(lens);
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> uni(0, 1);
        int passed = 0;
        for (int i = 0; i < 2000; ++i) {
            const Vec3 p{c.x + (uni(rng) - 0.5) * 0.2, c.y + (uni(rng) - 0.5) * 0.2, c.z - array.distance_mm};
            const ArrayRay up = array.microlens->sample_ray(array, p, lens, uni(rng), uni(rng));
            if (!up.passed)
                continue;
            ++passed;
            // The ray leaves from the array's plane: light coming back along it reaches p.
            EXPECT_NEAR(up.origin.z, c.z, 1e-12);
            // Light coming back enters through the face of exactly one lens (the sample's own or,
            // where the path crossed cells in the glass, a neighbour's).
            ArrayRay down{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}};
            int entries = 0;
            for (int dl = -2; dl <= 2; ++dl) {
                for (int dk = -2; dk <= 2; ++dk) {
                    const ArrayRay through = array.microlens->towards_sensor(array, LensIndex{lens.k + dk, lens.l + dl},
                                                                             up.origin, -1.0 * up.direction);
                    if (through.passed) {
                        ++entries;
                        down = through;
                    }
                }
            }
            ASSERT_EQ(entries, 1) << i;
            const Vec3 d = normalized(down.direction);
            const double travel = (p.z - down.origin.z) / d.z;
            EXPECT_NEAR(length(down.origin + travel * d - p), 0, 1e-10) << i;
        }
        EXPECT_GT(passed, 1000);
    }
}

TEST(RefractingMicrolens, LensesWithErrorsFocusOnTheirOwnAxis)
{
    // Manufacturing errors move, tilt and rescale each lens: light parallel to a lens's own axis,
    // near it, converges at its back focal point, the back focal distance of the thick lens from
    // the lensmaker's formula (f - L/n behind the flat back, or f behind the cap's vertex) along
    // the axis from its centre, with f the lens's own focal length.
    for (bool scene_side : {true, false}) {
        ArrayParams params;
        params.given = true;
        params.grid = GridType::Hexagonal;
        params.has_pitch = true;
        params.pitch_mm = 0.1;
        params.has_lens = true;
        params.lens = MicrolensType::Refracting;
        params.refracting = shape(scene_side, 0.08, 1.5, 0.025, 0.03);
        params.has_distance = true;
        params.distance_mm = 0.2;
        params.has_errors = true;
        params.errors.position_sd_mm = 0.002;
        params.errors.position_sd_z_mm = 0.002;
        params.errors.focal_sd = 0.05;
        params.errors.rotation_deg = 6;
        params.errors.seed = 3;
        const MicrolensArray array = make_microlens_array(params, -10);
        ASSERT_TRUE(array.errors);
        const double L = 0.025 + 0.03, n = 1.5;
        for (int k = -3; k <= 3; ++k) {
            const LensIndex lens{k, 1 - k};
            const LensError e = array.error_of(lens);
            const double f = array.focal_length_mm(lens);
            EXPECT_NEAR(f, 0.08 / 0.5 * e.focal_factor, 1e-15);
            const double bfd = scene_side ? f - L / n : f;
            const Vec3 c = array.centre_mm(lens);
            const Vec3 focus = c - bfd * e.axis;
            const Vec3 u = normalized(cross(e.axis, Vec3{1, 0, 0})), v = cross(e.axis, u);
            for (double a : {-1e-5, 2e-5})
                for (double b : {1e-5, -3e-5}) {
                    const Vec3 h = c + a * u + b * v;
                    const ArrayRay out = array.microlens->towards_sensor(array, lens, h, -1.0 * e.axis);
                    ASSERT_TRUE(out.passed);
                    EXPECT_LT(length(cross(focus - out.origin, normalized(out.direction))), 1e-9 * f)
                        << "lens " << k << ": the ray misses the back focal point";
                }
        }
    }
}

TEST(RefractingMicrolens, KindMetadataAndDispersion)
{
    const MicrolensArray array = refracting_array(true);
    EXPECT_STREQ(array.microlens->kind_name(), "refracting");
    EXPECT_TRUE(array.microlens->forms_image());
    EXPECT_FALSE(array.microlens->first_order_exact());
    EXPECT_NEAR(array.focal_length_mm(LensIndex{3, 3}), 0.08 / 0.5, 1e-15);
    // Power scaled by 1.1: n - 1 scaled by 1.1, the focal length divided by it.
    const std::shared_ptr<const Microlens> scaled = array.microlens->with_power_scaled(1.1);
    ASSERT_TRUE(scaled);
    EXPECT_NEAR(refracting_shape(*scaled)->ior, 1 + 0.5 * 1.1, 1e-15);
    EXPECT_NEAR(scaled->focal_length_mm(0), 0.16 / 1.1, 1e-14);
    EXPECT_EQ(refracting_shape(*make_thin_microlens(std::vector<double>{0.3, 0.3, 0.3}.data(), 1)), nullptr);
}

} // namespace
} // namespace plenoptic
