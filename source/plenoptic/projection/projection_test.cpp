// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of forward projection: chief rays back through the point, centroids of partly covered lenses.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/projection/projection.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::dir_of;
using test::origin_of;
using test::plenoptic_camera;
using test::str;
using test::thin_lens_camera;

// ---------------------------------------------------------------- forward projection

TEST(Optics, FocusedOnTheArrayImagesToTheCentreOfTheOnAxisMicroimage)
{
    // Plenoptic 1.0: d = f; the on-axis point whose thin-lens image lies on the array.
    const double F = 50, D = 52;
    for (GridType grid : {GridType::Hexagonal, GridType::Rectangular}) {
        const PlenopticCamera m = make_camera(plenoptic_camera(grid, 0.5, 2, 2, F, 4, D));
        const int W = 301, H = 201;
        const Vec3 point{0, 0, F * D / (D - F)};
        const std::vector<PixelHit> hits = with_film(m, W, H).project(point);
        ASSERT_EQ(hits.size(), 1u) << "only the lens on which the point is focused sees it";
        EXPECT_EQ(hits[0].lens, (LensIndex{0, 0}));
        EXPECT_NEAR(hits[0].u, (W - 1) / 2.0, 1e-9);
        EXPECT_NEAR(hits[0].v, (H - 1) / 2.0, 1e-9);
        double u, v;
        const MicroimageCentre centre_u = microimage_centre_px(with_film(m, W, H), LensIndex{0, 0});
        ASSERT_TRUE(centre_u.valid);
        u = centre_u.u;
        v = centre_u.v;
        EXPECT_NEAR(u, (W - 1) / 2.0, 1e-9);
        EXPECT_NEAR(v, (H - 1) / 2.0, 1e-9);
    }
}

// Whether the cone of light from the main aperture to the thin-lens image of x covers lens's
// cell only in part (thin lenses both; computed here without the code under test). Tilted
// arrays use the untilted footprint with a margin of a pitch: an over-approximation.
bool partly_covered(const PlenopticCamera& m, Vec3 x, LensIndex lens)
{
    if (test::lens_kind(m) != "thin_lens" || m.spec.array.lens != MicrolensType::ThinLens)
        return false;
    const double F = m.focal_length_mm(), D = m.distance_mm;
    const double b = F * x.z / (x.z - F);             // image distance behind the main lens
    const Vec2 image{-x.x * b / x.z, -x.y * b / x.z};  // image, laterally
    const Vec2 centre = (D / b) * image;               // cone axis at the array plane
    const double radius = 0.5 * m.aperture_mm() * std::fabs(b - D) / b;
    const Vec3 c3 = lens_centre_mm(m, lens);
    const double to_centre = length(Vec2{c3.x, c3.y} - centre);
    const double margin = m.array.pose.tilted ? m.array.pitch_mm : 1e-9;
    return to_centre + m.array.cell_circumradius_mm + margin > radius;
}

void check_forward_then_chief(const char* name, CameraParams params, int min_multi)
{
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
    ASSERT_EQ(check_camera(params), "") << name;
    const PlenopticCamera m = make_camera(params);
    const int W = 401, H = 301;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> depth(150.0, 3000.0), side(-0.03, 0.03);
    int hits_total = 0, multi = 0;
    for (int k = 0; k < 200; ++k) {
        const double z = depth(rng);
        const Vec3 point{side(rng) * z, side(rng) * z, z};
        const std::vector<PixelHit> hits = with_film(m, W, H).project(point);
        hits_total += int(hits.size());
        if (hits.size() >= 2)
            ++multi;
        for (const PixelHit& hit : hits) {
            EXPECT_TRUE(std::isfinite(hit.u) && std::isfinite(hit.v)) << name;
            EXPECT_GE(hit.u, -0.5);
            EXPECT_LT(hit.u, W - 0.5);
            OpticsRay ray;
            ASSERT_TRUE((ray = chief_ray_through(with_film(m, W, H), hit.u + 0.5, hit.v + 0.5, &hit.lens)).passed) << name;
            const Vec3 x{point.x, point.y, point.z};
            const double miss = test::distance_to_line(x, origin_of(ray), dir_of(ray));
            // A thin microlens that the point's cone of light covers only in part images it at
            // the centroid of that part, off the line through the lens centre
            // (ForwardProjectionIsTheCentroidOfTheLightThroughEachLens checks those hits).
            if (partly_covered(m, x, hit.lens))
                continue;
            // Nor is a spot that the picture's edge cuts (the image is the centroid of the part
            // inside): skip hits within the spot's reach of the edge.
            const double reach_px = (m.overlap.rings + 1) * m.array.pitch_mm * 2 / m.sensor.pixel_size_mm[0];
            if (hit.u < reach_px || hit.u > W - 1 - reach_px || hit.v < reach_px || hit.v > H - 1 - reach_px)
                continue;
            EXPECT_LT(miss, 1e-7 * z) << name << ": point " << str(x) << " lens (" << hit.lens.k << ","
                                      << hit.lens.l << ") at (" << hit.u << ", " << hit.v << ") chief ray misses by "
                                      << miss << " mm";
            // The hit lies in that lens's microimage cell or, where overlap is modelled, in the cell
            // of a lens within overlap_rings rings of it (the pixels that receive its light).
            const OwnLens owner_lookup = own_lens(m, with_film(m, W, H).sensor.point(hit.u + 0.5, hit.v + 0.5));
            ASSERT_TRUE(owner_lookup.found);
            const LensIndex owner = owner_lookup.lens;
            if (!m.overlap.modelled) {
                EXPECT_EQ(owner, hit.lens) << name;
            } else {
                const long long dk = skew_k(m.array.grid, owner) - skew_k(m.array.grid, hit.lens), dl = owner.l - hit.lens.l;
                long long rings = std::max(std::llabs(dk), std::llabs(dl));
                if (m.array.grid == GridType::Hexagonal)
                    rings = std::max(rings, std::llabs(dk + dl));
                EXPECT_LE(rings, m.overlap.rings) << name;
            }
        }
    }
    EXPECT_GT(hits_total, 100) << name;
    EXPECT_GE(multi, min_multi) << name << ": points seen by several microlenses";
}

TEST(Optics, ForwardProjectedPositionsTurnBackIntoChiefRaysThroughThePoint)
{
    check_forward_then_chief("focused 2.0", plenoptic_camera(GridType::Hexagonal, 0.2, 1.5, 2.0, 50, 4, 55), 50);
    CameraParams tilted = plenoptic_camera(GridType::Hexagonal, 0.2, 1.5, 2.0, 50, 4, 55);
    tilted.array.focal_length_count = 3;
    tilted.array.focal_lengths_mm[0] = 1.4;
    tilted.array.focal_lengths_mm[1] = 1.5;
    tilted.array.focal_lengths_mm[2] = 1.6;
    test::set_pose(&tilted, 1.5, -1, 25, 0.03, 0.01, 0.1);
    check_forward_then_chief("focused 2.0 tilted multi-focus", tilted, 50);
    check_forward_then_chief("plenoptic 1.0", plenoptic_camera(GridType::Rectangular, 0.2, 2.0, 2.0, 50, 8, 55), 20);
    check_forward_then_chief("pinhole array", plenoptic_camera(GridType::Hexagonal, 0.2, 0, 2.0, 50, 4, 55), 20);
    CameraParams pinhole_main;
    pinhole_main.main.given = true;
    pinhole_main.main.type = MainLensType::Pinhole;
    pinhole_main.main.has_distance = true;
    pinhole_main.main.distance_mm = 55;
    test::add_array(&pinhole_main, GridType::Hexagonal, 0.2, 1.5, 2.0);
    check_forward_then_chief("pinhole main lens", pinhole_main, 0);
    CameraParams bare;
    test::add_array(&bare, GridType::Rectangular, 0.2, 1.5, 2.0);
    test::set_pose(&bare, 0, 0, 10, 0, 0, 0);
    check_forward_then_chief("camera array", bare, 0);
}

// Light from a point, traced by brute force through the main aperture (uniform in area) and
// each microlens to the sensor: its centroid per lens is where forward_project says the point
// images. The tracer here is written from the rule w' = w - h/f of docs/specification.md
// (section 3), independently.
void check_forward_is_centroid(const char* name, const CameraParams& params, double max_px)
{
    ASSERT_EQ(check_camera(params), "") << name;
    const PlenopticCamera m = make_camera(params);
    const int W = 401, H = 301;
    const double F = m.focal_length_mm(), D = m.distance_mm, r = 0.5 * m.aperture_mm();
    const double d = m.array.distance_mm, sx = m.sensor.pixel_size_mm[0], sy = m.sensor.pixel_size_mm[1];
    int compared = 0;
    const double xs[][3] = {{3, -2, 400}, {-10, 6, 900}, {20, 12, 1500}, {0.4, -0.3, F * D / (D - F) * 1.02}};
    for (const auto& p : xs) {
        const std::vector<PixelHit> hits = with_film(m, W, H).project(Vec3{p[0], p[1], p[2]});
        std::map<std::pair<long long, long long>, std::array<double, 3>> sums;  // u, v, count
        std::mt19937_64 rng(11);
        std::uniform_real_distribution<double> uni(0, 1);
        for (int n = 0; n < 400000; ++n) {
            const double rho = r * std::sqrt(uni(rng)), phi = 2 * kPi * uni(rng);
            const double mx = rho * std::cos(phi), my = rho * std::sin(phi);
            // Slope (per unit +z) of the ray X -> aperture point, then undo the main lens.
            const double wx = (p[0] - mx) / p[2] + mx / F, wy = (p[1] - my) / p[2] + my / F;
            const double hx = mx - wx * D, hy = my - wy * D;
            const LensIndex lens = test::brute_force_nearest(m.array.grid, m.array.pitch_mm, hx, hy);
            const Vec2 c = lens_centre(m.array.grid, m.array.pitch_mm, lens);
            const double f = m.array.focal_length_mm(lens);
            const double bx = wx + (hx - c.x) / f, by = wy + (hy - c.y) / f;
            const double sxm = hx - bx * d, sym = hy - by * d;
            const double u = W / 2.0 - 0.5 - sxm / sx, v = H / 2.0 - 0.5 + sym / sy;
            auto& acc = sums[{lens.k, lens.l}];
            acc[0] += u;
            acc[1] += v;
            acc[2] += 1;
        }
        ASSERT_FALSE(hits.empty()) << name << ": point (" << p[0] << ", " << p[1] << ", " << p[2] << ") images nowhere";
        for (const PixelHit& hit : hits) {
            const auto it = sums.find({hit.lens.k, hit.lens.l});
            ASSERT_TRUE(it != sums.end()) << name << ": lens (" << hit.lens.k << "," << hit.lens.l << ") got no light";
            const double n = it->second[2];
            if (n < 2000)
                continue;  // a sliver: its brute-force centroid is too noisy to compare
            ++compared;
            const double u = it->second[0] / n, v = it->second[1] / n;
            EXPECT_LT(std::hypot(hit.u - u, hit.v - v), max_px)
                << name << ": point (" << p[0] << ", " << p[1] << ", " << p[2] << ") lens (" << hit.lens.k << ","
                << hit.lens.l << "): forward (" << hit.u << ", " << hit.v << ") vs light centroid (" << u << ", "
                << v << ") of " << n << " rays";
        }
    }
    EXPECT_GE(compared, 4) << name << ": too few lenses compared to mean anything";
}

TEST(Optics, ForwardProjectionIsTheCentroidOfTheLightThroughEachLens)
{
    check_forward_is_centroid("plenoptic 1.0 hex", plenoptic_camera(GridType::Hexagonal, 0.2, 0.8, 0.8, 50, 4, 55), 0.05);
    check_forward_is_centroid("plenoptic 1.0 rect", plenoptic_camera(GridType::Rectangular, 0.2, 0.8, 0.8, 50, 4, 55), 0.05);
    check_forward_is_centroid("focused 2.0 hex", plenoptic_camera(GridType::Hexagonal, 0.2, 1.5, 2.0, 50, 4, 55), 0.05);
}

TEST(Optics, ForwardProjectionWithoutArrayIsThePerspectiveProjection)
{
    const PlenopticCamera m = make_camera(thin_lens_camera(50, 4, 52));
    const int W = 640, H = 480;
    const Vec3 point{100, -50, 2000};
    const std::vector<PixelHit> hits = with_film(m, W, H).project(point);
    ASSERT_EQ(hits.size(), 1u);
    // Inverted on the sensor: x = -100 * 52 / 2000 = -2.6 mm, y = +1.3 mm; read out upright:
    // right of the axis -> right of the image (u = 319.5 + 260), below -> below (v = 239.5 + 130).
    EXPECT_NEAR(hits[0].u, 319.5 + 2.6 / 0.01, 1e-9);
    EXPECT_NEAR(hits[0].v, 239.5 + 1.3 / 0.01, 1e-9);
    const Vec3 behind{0, 0, -10};
    EXPECT_TRUE(with_film(m, W, H).project(behind).empty());
}

} // namespace
} // namespace plenoptic
