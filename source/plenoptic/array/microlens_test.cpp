// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the microlens array and its kinds of lens against geometry written out here: lens
// centres from the lattice formulas and textbook rotations, the thin-lens equation, straight lines
// through pinholes.

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/array/array_params.h"
#include "plenoptic/array/microlens_array.h"

namespace plenoptic {
namespace {

// The textbook right-hand-rule rotations, about x first, then y, then z.
Vec3 rotate(const double deg[3], Vec3 v)
{
    const double ax = deg[0] * kPi / 180, ay = deg[1] * kPi / 180, az = deg[2] * kPi / 180;
    const Vec3 a{v.x, std::cos(ax) * v.y - std::sin(ax) * v.z, std::sin(ax) * v.y + std::cos(ax) * v.z};
    const Vec3 b{std::cos(ay) * a.x + std::sin(ay) * a.z, a.y, -std::sin(ay) * a.x + std::cos(ay) * a.z};
    return Vec3{std::cos(az) * b.x - std::sin(az) * b.y, std::sin(az) * b.x + std::cos(az) * b.y, b.z};
}

// Lens centre in the array's plane by the specification's row form.
Vec2 centre_by_formula(GridType grid, double p, LensIndex lens)
{
    if (grid == GridType::Rectangular)
        return Vec2{double(lens.k) * p, double(lens.l) * p};
    const long long odd = ((lens.l % 2) + 2) % 2;
    return Vec2{(double(lens.k) + 0.5 * double(odd)) * p, double(lens.l) * p * std::sqrt(3.0) / 2};
}

double distance_to_line(Vec3 x, Vec3 origin, Vec3 direction)
{
    return length(cross(x - origin, direction)) / length(direction);
}

ArrayParams array_params(GridType grid, double pitch, int focal_count, double f0, double f1 = 0, double f2 = 0)
{
    ArrayParams a;
    a.given = true;
    a.grid = grid;
    a.has_pitch = true;
    a.pitch_mm = pitch;
    a.has_lens = true;
    a.lens = focal_count == 0 ? MicrolensType::Pinhole : MicrolensType::ThinLens;
    a.focal_length_count = focal_count;
    a.focal_lengths_mm[0] = f0;
    a.focal_lengths_mm[1] = f1;
    a.focal_lengths_mm[2] = f2;
    a.has_distance = true;
    a.distance_mm = 0.7;
    return a;
}

TEST(MicrolensArray, EachKindAnswersForItself)
{
    const MicrolensArray pinholes = make_microlens_array(array_params(GridType::Rectangular, 0.1, 0, 0), -50);
    ASSERT_TRUE(pinholes.present());
    EXPECT_STREQ(pinholes.microlens->kind_name(), "pinhole");
    EXPECT_FALSE(pinholes.microlens->forms_image());
    EXPECT_TRUE(pinholes.microlens->focal_lengths_mm().empty());
    EXPECT_EQ(pinholes.lens_type_count, 1);

    const MicrolensArray thin = make_microlens_array(array_params(GridType::Hexagonal, 0.1, 1, 0.4), -50);
    EXPECT_STREQ(thin.microlens->kind_name(), "thin_lens");
    EXPECT_TRUE(thin.microlens->forms_image());
    EXPECT_EQ(thin.microlens->focal_lengths_mm(), std::vector<double>({0.4}));
    EXPECT_EQ(thin.lens_type_count, 1);
    EXPECT_EQ(thin.focal_length_mm(LensIndex{5, -3}), 0.4);

    const MicrolensArray multi = make_microlens_array(array_params(GridType::Hexagonal, 0.1, 3, 0.4, 0.5, 0.6), -50);
    EXPECT_EQ(multi.microlens->focal_lengths_mm(), std::vector<double>({0.4, 0.5, 0.6}));
    EXPECT_EQ(multi.lens_type_count, 3);
    // The type rule written out: skew index k_s = k - floor(l / 2), type = (k_s - l) mod 3.
    for (long long l = -4; l <= 4; ++l)
        for (long long k = -4; k <= 4; ++k) {
            const long long ks = k - (long long)std::floor(l / 2.0);
            const int type = int((((ks - l) % 3) + 3) % 3);
            EXPECT_EQ(multi.type_of(LensIndex{k, l}), type) << k << ", " << l;
            const double given[3] = {0.4, 0.5, 0.6};
            EXPECT_EQ(multi.focal_length_mm(LensIndex{k, l}), given[type]) << k << ", " << l;
        }

    ArrayParams none;
    const MicrolensArray absent = make_microlens_array(none, -50);
    EXPECT_FALSE(absent.present());
    EXPECT_EQ(absent.microlens, nullptr);
    EXPECT_EQ(absent.pose.centre_mm.z, -50);
    EXPECT_FALSE(absent.pose.tilted);
}

TEST(MicrolensArray, PlacesItsLensesByTheLatticeAndThePose)
{
    for (GridType grid : {GridType::Rectangular, GridType::Hexagonal}) {
        ArrayParams a = array_params(grid, 0.13, 1, 0.4);
        const double deg[3] = {3, -2, 7};
        for (int i = 0; i < 3; ++i)
            a.rotate_deg[i] = deg[i];
        a.translate_mm[0] = 0.02;
        a.translate_mm[1] = -0.05;
        a.translate_mm[2] = 0.3;
        const MicrolensArray array = make_microlens_array(a, -60);
        const Vec3 origin{0.02, -0.05, -60 + 0.3};
        EXPECT_TRUE(array.pose.tilted);
        EXPECT_LT(length(array.pose.normal - rotate(deg, Vec3{0, 0, 1})), 1e-15);
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> uni(-3, 3);
        for (int n = 0; n < 2000; ++n) {
            const LensIndex lens{(long long)std::floor(uni(rng) * 10), (long long)std::floor(uni(rng) * 10)};
            const Vec2 c = centre_by_formula(grid, 0.13, lens);
            const Vec3 expected = origin + rotate(deg, Vec3{c.x, c.y, 0});
            EXPECT_LT(length(array.centre_mm(lens) - expected), 1e-12);
            // The lens whose cell holds a point is the one with the nearest centre.
            const double x = uni(rng), y = uni(rng);
            const LensIndex found = array.nearest(x, y);
            const double own = length(Vec2{x, y} - centre_by_formula(grid, 0.13, found));
            for (long long dl = -2; dl <= 2; ++dl)
                for (long long dk = -2; dk <= 2; ++dk)
                    EXPECT_LE(own, length(Vec2{x, y} - centre_by_formula(grid, 0.13, LensIndex{found.k + dk, found.l + dl})) + 1e-12);
            const Vec3 q{uni(rng), uni(rng), uni(rng) - 60};
            EXPECT_LT(length(array.to_optics(array.to_local(q)) - q), 1e-12);
        }
    }
}

// A sensor point p, d behind an array (untilted, or tilted: everything in its own frame), imaged
// by a thin lens of focal length f centred at c: every ray from p through the lens passes the
// image I = c + (c - p) b / d at height b in front of the lens, 1/b = 1/f - 1/d (b < 0: a virtual
// image behind it, which the rays leave as if they came from it); for f = d the image is at
// infinity and every ray leaves parallel to the line p -> c.
TEST(ThinMicrolens, RaysFromASensorPointPassItsImage)
{
    const double deg[3] = {4, -3, 20};
    for (bool tilted : {false, true})
        for (double f : {0.5, 0.7, 1.1}) {
            ArrayParams a = array_params(GridType::Hexagonal, 0.15, 1, f);
            if (tilted)
                for (int i = 0; i < 3; ++i)
                    a.rotate_deg[i] = deg[i];
            const MicrolensArray array = make_microlens_array(a, -50);
            const double none[3] = {0, 0, 0};
            const double* pose = tilted ? deg : none;
            const double d = 0.7;
            const LensIndex lens{2, -1};
            const Vec2 c = centre_by_formula(GridType::Hexagonal, 0.15, lens);
            const Vec3 p_local{c.x + 0.031, c.y - 0.017, -d};
            const Vec3 p = Vec3{0, 0, -50} + rotate(pose, p_local);
            const double b = 1 / (1 / f - 1 / d);
            const Vec3 image_local{c.x + (c.x - p_local.x) * b / d, c.y + (c.y - p_local.y) * b / d, b};
            const Vec3 image = Vec3{0, 0, -50} + rotate(pose, image_local);
            for (double u : {0.1, 0.5, 0.83})
                for (double v : {0.05, 0.5, 0.97}) {
                    const ArrayRay ray = array.microlens->sample_ray(array, p, lens, u, v);
                    ASSERT_TRUE(ray.passed);
                    // It leaves from the lens's plane, inside the lens's cell.
                    const Vec3 h = array.to_local(ray.origin);
                    EXPECT_NEAR(h.z, 0, 1e-12);
                    EXPECT_TRUE(array.nearest(h.x, h.y) == lens);
                    if (f == d) {
                        const Vec3 axis = rotate(pose, Vec3{c.x - p_local.x, c.y - p_local.y, d});
                        EXPECT_LT(length(cross(axis, ray.direction)) / length(axis) / length(ray.direction), 1e-12) << u << " " << v;
                    } else {
                        EXPECT_LT(distance_to_line(image, ray.origin, ray.direction), 1e-9) << f << " " << u << " " << v;
                    }
                    EXPECT_GT(dot(ray.direction, array.pose.normal), 0);
                    // Light travelling back along it is bent to the sensor point.
                    const ArrayRay back = array.microlens->towards_sensor(array, lens, ray.origin, -ray.direction);
                    ASSERT_TRUE(back.passed);
                    EXPECT_LT(distance_to_line(p, back.origin, back.direction), 1e-12);
                    EXPECT_LT(dot(back.direction, array.pose.normal), 0);
                }
            // A sensor point in front of the array has no ray.
            EXPECT_FALSE(array.microlens->sample_ray(array, Vec3{p.x, p.y, -49}, lens, 0.5, 0.5).passed);
        }
}

TEST(PinholeMicrolens, ItsOnlyRayPassesTheCentreStraight)
{
    ArrayParams a = array_params(GridType::Rectangular, 0.15, 0, 0);
    a.rotate_deg[0] = 5;
    const MicrolensArray array = make_microlens_array(a, -50);
    const LensIndex lens{-3, 2};
    const Vec3 centre = array.centre_mm(lens);
    const Vec3 p{0.1, -0.2, -50.8};
    for (double u : {0.1, 0.5, 0.9}) {
        const ArrayRay ray = array.microlens->sample_ray(array, p, lens, u, 1 - u);
        ASSERT_TRUE(ray.passed);
        EXPECT_LT(length(ray.origin - centre), 1e-15);
        EXPECT_LT(distance_to_line(p, ray.origin, ray.direction), 1e-12);
        EXPECT_GT(dot(ray.direction, array.pose.normal), 0);
    }
    // Light arriving anywhere goes on unchanged; no ray from p heads for a given point.
    const ArrayRay through = array.microlens->towards_sensor(array, lens, centre, Vec3{0.1, 0.2, -1});
    ASSERT_TRUE(through.passed);
    EXPECT_LT(length(through.direction - Vec3{0.1, 0.2, -1}), 1e-15);
    EXPECT_FALSE(array.microlens->ray_through(array, p, lens, Vec3{0, 0, 0}, false).passed);
    EXPECT_FALSE(array.microlens->sample_ray(array, Vec3{0, 0, -49}, lens, 0.5, 0.5).passed);
}

// The ray from p through a thin lens that heads for a point O: traced back from O, it meets the
// lens's plane at some h, and the thin-lens rule written out here (unit travel along the normal,
// w' = w - (h - c) / f) turns the direction from p to h into the direction from h to O.
TEST(ThinMicrolens, RayThroughATargetObeysTheThinLensRule)
{
    const double f = 0.6;
    const MicrolensArray array = make_microlens_array(array_params(GridType::Rectangular, 0.15, 1, f), -50);
    const Vec3 target{0, 0, 0};
    for (const LensIndex lens : {LensIndex{0, 0}, LensIndex{3, -2}, LensIndex{-7, 5}}) {
        const Vec2 c = centre_by_formula(GridType::Rectangular, 0.15, lens);
        const Vec3 p{c.x * 1.012 + 0.02, c.y * 1.012 - 0.01, -50.7};
        const ArrayRay ray = array.microlens->ray_through(array, p, lens, target, false);
        ASSERT_TRUE(ray.passed);
        EXPECT_EQ(ray.origin.x, 0);
        EXPECT_EQ(ray.origin.z, 0);
        const double t = (-50 - target.z) / ray.direction.z;
        const Vec3 h = target + t * ray.direction;
        const Vec3 in{(h.x - p.x) / (h.z - p.z), (h.y - p.y) / (h.z - p.z), 1};
        const Vec3 out{in.x - (h.x - c.x) / f, in.y - (h.y - c.y) / f, 1};
        const Vec3 seen{ray.direction.x / ray.direction.z, ray.direction.y / ray.direction.z, 1};
        EXPECT_LT(length(out - seen), 1e-9) << lens.k << ", " << lens.l;
        // With the cell checked, it passes only if h is in the lens's cell.
        const bool inside = array.nearest(h.x, h.y) == lens;
        EXPECT_EQ(array.microlens->ray_through(array, p, lens, target, true).passed, inside);
    }
    // A sensor point far off the lens: the ray crosses the plane in another lens's cell.
    const Vec3 far{3, 0, -50.7};
    EXPECT_TRUE(array.microlens->ray_through(array, far, LensIndex{0, 0}, target, false).passed);
    EXPECT_FALSE(array.microlens->ray_through(array, far, LensIndex{0, 0}, target, true).passed);
}

} // namespace
} // namespace plenoptic
