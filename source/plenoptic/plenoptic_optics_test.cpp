// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the optics: axis, conjugates, lookup through the pose, round trips, forward projection.

#include <cmath>
#include <array>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic_optics.h"
#include "plenoptic_test_util.h"

namespace plenoptic {
namespace {

using test::dir_of;
using test::origin_of;
using test::plenoptic_camera;
using test::str;
using test::thin_lens_camera;

const CameraSample kCentreSample{0.5, 0.5, 0.5, 0.5};

// ---------------------------------------------------------------- the optical axis

TEST(Optics, SensorPointConvention)
{
    CameraParams p = thin_lens_camera(50, 4, 52);
    p.sensor.pixel_size_mm[0] = 0.01;
    p.sensor.pixel_size_mm[1] = 0.02;
    p.sensor.offset_mm[0] = 0.3;
    p.sensor.offset_mm[1] = -0.1;
    const Model m = make_model(p);
    const int W = 640, H = 480;
    // Pixel (i, j)'s centre: x = -((i + 0.5) - W/2) sx + ox, y = ((j + 0.5) - H/2) sy + oy.
    const Vec3 c = sensor_point(m, W, H, 10 + 0.5, 20 + 0.5);
    EXPECT_DOUBLE_EQ(c.x, -((10 + 0.5) - 320) * 0.01 + 0.3);
    EXPECT_DOUBLE_EQ(c.y, ((20 + 0.5) - 240) * 0.02 - 0.1);
    EXPECT_DOUBLE_EQ(c.z, -52);
    double u, v;
    EXPECT_TRUE(sensor_to_pixel(m, W, H, c.x, c.y, &u, &v));
    EXPECT_NEAR(u, 10, 1e-9);
    EXPECT_NEAR(v, 20, 1e-9);
    const Vec2 principal = principal_point_px(m, W, H);
    EXPECT_NEAR(principal.x, 319.5 + 30, 1e-9);
    EXPECT_NEAR(principal.y, 239.5 + 5, 1e-9);
}

void expect_axis(const OpticsRay& ray, const char* what)
{
    EXPECT_NEAR(ray.origin_mm[0], 0, 1e-15) << what;
    EXPECT_NEAR(ray.origin_mm[1], 0, 1e-15) << what;
    EXPECT_NEAR(ray.origin_mm[2], 0, 1e-15) << what;
    EXPECT_NEAR(ray.dir[0], 0, 1e-15) << what << " direction " << str(dir_of(ray));
    EXPECT_NEAR(ray.dir[1], 0, 1e-15) << what << " direction " << str(dir_of(ray));
    EXPECT_NEAR(ray.dir[2], 1, 1e-15) << what << " direction " << str(dir_of(ray));
}

TEST(Optics, CentreSampleGivesTheOpticalAxis)
{
    const int W = 101, H = 101;  // pixel (50, 50) is centred on the axis
    OpticsRay ray;
    ASSERT_TRUE(generate_ray(make_model(thin_lens_camera(50, 4, 52)), W, H, 50, 50, kCentreSample, nullptr, &ray));
    expect_axis(ray, "thin lens, no array");

    for (GridType grid : {GridType::Hexagonal, GridType::Rectangular}) {
        ASSERT_TRUE(generate_ray(make_model(plenoptic_camera(grid, 0.5, 2, 2, 50, 4, 52)), W, H, 50, 50,
                                 kCentreSample, nullptr, &ray));
        expect_axis(ray, "plenoptic 1.0");
        ASSERT_TRUE(generate_ray(make_model(plenoptic_camera(grid, 0.5, 0, 2, 50, 4, 52)), W, H, 50, 50,
                                 kCentreSample, nullptr, &ray));
        expect_axis(ray, "pinhole array");
    }
    CameraParams pinhole_main;
    pinhole_main.main.given = true;
    pinhole_main.main.type = MainLensType::Pinhole;
    pinhole_main.main.has_distance = true;
    pinhole_main.main.distance_mm = 52;
    test::add_array(&pinhole_main, GridType::Hexagonal, 0.5, 1.5, 2);
    ASSERT_EQ(check_camera(pinhole_main), "");
    ASSERT_TRUE(generate_ray(make_model(pinhole_main), W, H, 50, 50, kCentreSample, nullptr, &ray));
    expect_axis(ray, "pinhole main lens, thin array");
}

// ---------------------------------------------------------------- conjugates

TEST(Optics, RaysFromASensorPointMeetAtTheThinLensConjugate)
{
    const double F = 50, D = 60;
    const Model m = make_model(thin_lens_camera(F, 2.8, D));
    const int W = 101, H = 101, i = 10, j = 80;
    const Vec3 p = sensor_point(m, W, H, i + 0.5, j + 0.5);
    // Independently: 1/u = 1/F - 1/D, lateral magnification -u/D.
    const double u = 1 / (1 / F - 1 / D);
    const Vec3 conjugate{-p.x * u / D, -p.y * u / D, u};
    double spread = 0;
    for (int n = 0; n < 200; ++n) {
        CameraSample s = make_sample(i, j, n, 200);
        s.pixel_u = s.pixel_v = 0.5;  // one sensor point, many lens points
        OpticsRay ray;
        ASSERT_TRUE(generate_ray(m, W, H, i, j, s, nullptr, &ray));
        const double miss = test::distance_to_line(conjugate, origin_of(ray), dir_of(ray));
        EXPECT_LT(miss, 1e-9 * u) << "sample " << n << " origin " << str(origin_of(ray)) << " misses "
                                  << str(conjugate) << " by " << miss;
        spread = std::max(spread, length(origin_of(ray)));
    }
    EXPECT_GT(spread, 0.4 * m.aperture_mm / 2);  // the rays really cover the aperture
}

TEST(Optics, SensorAtTheFocalPlaneGivesParallelRays)
{
    const double F = 50;
    const Model m = make_model(thin_lens_camera(F, 2.8, F));  // D = F exactly
    const int W = 101, H = 101, i = 3, j = 77;
    const Vec3 p = sensor_point(m, W, H, i + 0.5, j + 0.5);
    const Vec3 expected = normalized(-p);
    for (int n = 0; n < 100; ++n) {
        CameraSample s = make_sample(i, j, n, 100);
        s.pixel_u = s.pixel_v = 0.5;
        OpticsRay ray;
        ASSERT_TRUE(generate_ray(m, W, H, i, j, s, nullptr, &ray));
        EXPECT_LT(length(dir_of(ray) - expected), 1e-14) << "sample " << n << " " << str(dir_of(ray));
    }
}

// A bare thin-lens microlens array (no main lens), optionally tilted: rays from one sensor point
// through one microlens meet at that microlens's conjugate of the point, or are parallel at d = f.
void check_microlens_conjugate(double f, double d, const double pose_deg[3])
{
    CameraParams params;
    test::add_array(&params, GridType::Hexagonal, 0.5, f, d);
    test::set_pose(&params, pose_deg[0], pose_deg[1], pose_deg[2], 0.02, -0.03, 0);
    ASSERT_EQ(check_camera(params), "");
    const Model m = make_model(params);
    const int W = 200, H = 200, i = 120, j = 61;
    const Vec3 p = sensor_point(m, W, H, i + 0.5, j + 0.5);
    // Lens and distances in the array's frame, computed here with the reference rotation.
    const Vec3 centre = m.pose.centre_mm;
    const Vec3 n = test::reference_rotate(pose_deg, Vec3{0, 0, 1});
    const Vec3 foot = p + Vec3{0, 0, dot(n, centre - p) / n.z};
    const Vec3 foot_local = test::reference_unrotate(pose_deg, foot - centre);
    const LensIndex lens = test::brute_force_nearest(GridType::Hexagonal, 0.5, foot_local.x, foot_local.y);
    const Vec2 c2 = lens_centre(GridType::Hexagonal, 0.5, lens);
    const Vec3 c_local{c2.x, c2.y, 0};
    const Vec3 p_local = test::reference_unrotate(pose_deg, p - centre);
    const double behind = -p_local.z;
    bool parallel = f == d;
    Vec3 target{0, 0, 0};
    if (!parallel) {
        const double u = 1 / (1 / f - 1 / behind);
        const Vec3 x_local = c_local + (u / behind) * (c_local - p_local);
        target = centre + test::reference_rotate(pose_deg, x_local);
    }
    const Vec3 chief = normalized(test::reference_rotate(pose_deg, c_local - p_local));
    for (int k = 0; k < 100; ++k) {
        CameraSample s = make_sample(i, j, k, 100);
        s.pixel_u = s.pixel_v = 0.5;
        OpticsRay ray;
        ASSERT_TRUE(generate_ray(m, W, H, i, j, s, nullptr, &ray));
        if (parallel) {
            EXPECT_LT(length(dir_of(ray) - chief), 1e-13) << "sample " << k << " " << str(dir_of(ray))
                                                          << " vs " << str(chief);
        } else {
            const double miss = test::distance_to_line(target, origin_of(ray), dir_of(ray));
            EXPECT_LT(miss, 1e-9 * length(target - centre)) << "sample " << k << " misses " << str(target);
        }
    }
}

TEST(Optics, MicrolensConjugateAndParallelRays)
{
    const double flat[3] = {0, 0, 0};
    const double posed[3] = {5, -3, 20};
    check_microlens_conjugate(2.0, 2.5, flat);
    check_microlens_conjugate(2.0, 2.0, flat);
    check_microlens_conjugate(2.0, 2.5, posed);
}

// ---------------------------------------------------------------- lookup through the pose

void check_posed_lookup(GridType grid, bool with_main_lens)
{
    const double deg[3] = {3, -2, 33};
    CameraParams params = plenoptic_camera(grid, 0.13, 0.6, 0.6, 50, 4, 52);
    if (!with_main_lens)
        params.main = MainLensParams();
    test::set_pose(&params, deg[0], deg[1], deg[2], 0.05, -0.02, 0.1);
    ASSERT_EQ(check_camera(params), "");
    const Model m = make_model(params);
    const Vec3 centre = m.pose.centre_mm;
    const Vec3 n = test::reference_rotate(deg, Vec3{0, 0, 1});
    std::mt19937_64 rng(2024);
    std::uniform_real_distribution<double> coordinate(-5.0, 5.0);
    int failures = 0;
    for (int k = 0; k < 100000 && failures < 5; ++k) {
        const Vec3 p{coordinate(rng), coordinate(rng), m.sensor_z_mm};
        Vec3 q;
        if (with_main_lens)
            q = (dot(n, centre) / dot(n, p)) * p;  // line from the main-lens centre
        else
            q = p + Vec3{0, 0, dot(n, centre - p) / n.z};  // straight up
        const Vec3 local = test::reference_unrotate(deg, q - centre);
        const LensIndex expected = test::brute_force_nearest(grid, 0.13, local.x, local.y);
        LensIndex found;
        ASSERT_TRUE(own_lens(m, p, &found));
        if (found != expected) {
            const Vec2 a = lens_centre(grid, 0.13, found), b = lens_centre(grid, 0.13, expected);
            const double da = std::hypot(local.x - a.x, local.y - a.y), db = std::hypot(local.x - b.x, local.y - b.y);
            if (da > db + 1e-9) {
                ++failures;
                ADD_FAILURE() << "sensor point " << str(p) << ": lens (" << found.k << "," << found.l
                              << ") at " << da << ", brute force (" << expected.k << "," << expected.l << ") at " << db;
            }
        }
    }
}

TEST(Optics, LensLookupThroughRotatedShiftedArrayMatchesBruteForce)
{
    check_posed_lookup(GridType::Hexagonal, true);
    check_posed_lookup(GridType::Rectangular, true);
    check_posed_lookup(GridType::Hexagonal, false);
    check_posed_lookup(GridType::Rectangular, false);
}

// ---------------------------------------------------------------- round trip

struct RoundTripCase {
    const char* name;
    CameraParams params;
};

// Traces a generated ray backwards through the same ideal elements, computed here independently,
// to the sensor plane.
Vec3 trace_back(const Model& m, const CameraParams& params, const OpticsRay& ray, std::string* failure)
{
    const double* deg = params.array.rotate_deg;
    Vec3 at = origin_of(ray);
    Vec3 back;  // direction of travel towards the sensor, unit z magnitude where relevant
    const Vec3 d = dir_of(ray);
    if (m.main_lens == MainLensType::ThinLens) {
        // Undo w' = w - m/F at the main lens.
        back = -Vec3{d.x / d.z + at.x / m.focal_length_mm, d.y / d.z + at.y / m.focal_length_mm, 1};
    } else {
        back = -d;
    }
    if (m.grid == GridType::None) {
        const double t = (m.sensor_z_mm - at.z) / back.z;
        return at + t * back;
    }
    // Meet the posed array plane.
    const Vec3 centre{params.array.translate_mm[0], params.array.translate_mm[1],
                      (m.main_lens == MainLensType::None ? 0 : -m.distance_mm) + params.array.translate_mm[2]};
    const Vec3 n = test::reference_rotate(deg, Vec3{0, 0, 1});
    if (m.main_lens != MainLensType::None) {
        const double t = dot(n, centre - at) / dot(n, back);
        at = at + t * back;
    }
    const Vec3 h_local = test::reference_unrotate(deg, at - centre);
    const LensIndex lens = test::brute_force_nearest(m.grid, m.pitch_mm, h_local.x, h_local.y);
    const Vec2 c = lens_centre(m.grid, m.pitch_mm, lens);
    Vec3 w = test::reference_unrotate(deg, back);
    w = (1 / -w.z) * w;  // unit travel along -z_local
    if (m.microlens == MicrolensType::ThinLens) {
        // Type rule written out here: skew k = k - floor(l/2), type = (k_s - l) mod 3.
        int type = 0;
        if (m.lens_type_count == 3) {
            const long long l = lens.l, ks = lens.k - (l >= 0 ? l / 2 : -((-l + 1) / 2));
            type = int((((ks - l) % 3) + 3) % 3);
        }
        const double f = m.microlens_focal_mm[type];
        // Undo the microlens: sensor-side slope = scene-side slope - (h - c)/f for this direction.
        w = Vec3{w.x - (h_local.x - c.x) / f, w.y - (h_local.y - c.y) / f, -1};
    } else if (std::hypot(h_local.x - c.x, h_local.y - c.y) > 1e-9) {
        *failure = "ray does not pass the pinhole's centre";
    }
    const Vec3 down = test::reference_rotate(deg, w);
    const double t = (m.sensor_z_mm - at.z) / down.z;
    return at + t * down;
}

TEST(Optics, PixelToRayToSensorRoundTrip)
{
    std::vector<RoundTripCase> cases;
    cases.push_back({"thin + thin hex, flat", plenoptic_camera(GridType::Hexagonal, 0.3, 1.5, 2.0, 50, 4, 55)});
    CameraParams tilted = plenoptic_camera(GridType::Hexagonal, 0.3, 1.5, 2.0, 50, 4, 55);
    tilted.array.focal_length_count = 3;
    tilted.array.focal_lengths_mm[0] = 1.4;
    tilted.array.focal_lengths_mm[1] = 1.5;
    tilted.array.focal_lengths_mm[2] = 1.7;
    test::set_pose(&tilted, 2, -1.5, 10, 0.07, -0.04, 0.2);
    cases.push_back({"thin + thin multi-focus, tilted", tilted});
    CameraParams pinholes = plenoptic_camera(GridType::Rectangular, 0.3, 0, 2.0, 50, 2, 55);
    test::set_pose(&pinholes, -1, 2, -7, 0.01, 0.02, -0.1);
    cases.push_back({"thin + pinhole rect, tilted", pinholes});
    CameraParams pinhole_main;
    pinhole_main.main.given = true;
    pinhole_main.main.type = MainLensType::Pinhole;
    pinhole_main.main.has_distance = true;
    pinhole_main.main.distance_mm = 55;
    test::add_array(&pinhole_main, GridType::Hexagonal, 0.3, 1.5, 2.0);
    test::set_pose(&pinhole_main, 1, 1, 15, 0, 0.05, 0);
    cases.push_back({"pinhole + thin, tilted", pinhole_main});
    CameraParams bare;
    test::add_array(&bare, GridType::Hexagonal, 0.3, 1.5, 2.0);
    test::set_pose(&bare, 3, -2, 40, 0.03, 0, 0.1);
    cases.push_back({"no main lens, thin array, tilted", bare});
    cases.push_back({"thin lens, no array", thin_lens_camera(50, 2, 55)});

    const int W = 120, H = 90;
    for (RoundTripCase& c : cases) {
        c.params.sensor.pixel_size_mm[0] = c.params.sensor.pixel_size_mm[1] = 0.02;
        ASSERT_EQ(check_camera(c.params), "") << c.name;
        const Model m = make_model(c.params);
        int traced = 0;
        double worst = 0;
        for (int j = 0; j < H; j += 7) {
            for (int i = 0; i < W; i += 5) {
                for (int n = 0; n < 8; ++n) {
                    const CameraSample s = make_sample(i, j, n, 8);
                    OpticsRay ray;
                    if (!generate_ray(m, W, H, i, j, s, nullptr, &ray))
                        continue;
                    std::string failure;
                    const Vec3 back = trace_back(m, c.params, ray, &failure);
                    const Vec3 start = sensor_point(m, W, H, i + s.pixel_u, j + s.pixel_v);
                    EXPECT_TRUE(failure.empty()) << c.name << ": " << failure;
                    worst = std::max(worst, length(back - start));
                    EXPECT_LT(length(back - start), 1e-9) << c.name << " pixel " << i << "," << j << " sample " << n
                                                          << ": " << str(start) << " -> " << str(back);
                    ++traced;
                }
            }
        }
        // A pinhole main lens lights only ~10% of each microimage cell here; the rest pass more.
        EXPECT_GT(traced, 100) << c.name << ": too few unblocked rays to mean anything";
        RecordProperty(std::string("worst_round_trip_mm_") + c.name, std::to_string(worst));
    }
}

// ---------------------------------------------------------------- forward projection

TEST(Optics, FocusedOnTheArrayImagesToTheCentreOfTheOnAxisMicroimage)
{
    // Plenoptic 1.0: d = f; the on-axis point whose thin-lens image lies on the array.
    const double F = 50, D = 52;
    for (GridType grid : {GridType::Hexagonal, GridType::Rectangular}) {
        const Model m = make_model(plenoptic_camera(grid, 0.5, 2, 2, F, 4, D));
        const int W = 301, H = 201;
        const double point[3] = {0, 0, F * D / (D - F)};
        const std::vector<PixelHit> hits = forward_project(m, W, H, point);
        ASSERT_EQ(hits.size(), 1u) << "only the lens on which the point is focused sees it";
        EXPECT_EQ(hits[0].lens, (LensIndex{0, 0}));
        EXPECT_NEAR(hits[0].u, (W - 1) / 2.0, 1e-9);
        EXPECT_NEAR(hits[0].v, (H - 1) / 2.0, 1e-9);
        double u, v;
        ASSERT_TRUE(microimage_centre_px(m, W, H, LensIndex{0, 0}, &u, &v));
        EXPECT_NEAR(u, (W - 1) / 2.0, 1e-9);
        EXPECT_NEAR(v, (H - 1) / 2.0, 1e-9);
    }
}

// Whether the cone of light from the main aperture to the thin-lens image of x covers lens's
// cell only in part (thin lenses both; computed here without the code under test). Tilted
// arrays use the untilted footprint with a margin of a pitch: an over-approximation.
bool partly_covered(const Model& m, Vec3 x, LensIndex lens)
{
    if (m.main_lens != MainLensType::ThinLens || m.microlens != MicrolensType::ThinLens)
        return false;
    const double F = m.focal_length_mm, D = m.distance_mm;
    const double b = F * x.z / (x.z - F);             // image distance behind the main lens
    const Vec2 image{-x.x * b / x.z, -x.y * b / x.z};  // image, laterally
    const Vec2 centre = (D / b) * image;               // cone axis at the array plane
    const double radius = 0.5 * m.aperture_mm * std::fabs(b - D) / b;
    const Vec3 c3 = lens_centre_mm(m, lens);
    const double to_centre = length(Vec2{c3.x, c3.y} - centre);
    const double margin = m.pose.tilted ? m.pitch_mm : 1e-9;
    return to_centre + m.cell_circumradius_mm + margin > radius;
}

void check_forward_then_chief(const char* name, CameraParams params, int min_multi)
{
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
    ASSERT_EQ(check_camera(params), "") << name;
    const Model m = make_model(params);
    const int W = 401, H = 301;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> depth(150.0, 3000.0), side(-0.03, 0.03);
    int hits_total = 0, multi = 0;
    for (int k = 0; k < 200; ++k) {
        const double z = depth(rng);
        const double point[3] = {side(rng) * z, side(rng) * z, z};
        const std::vector<PixelHit> hits = forward_project(m, W, H, point);
        hits_total += int(hits.size());
        if (hits.size() >= 2)
            ++multi;
        for (const PixelHit& hit : hits) {
            EXPECT_TRUE(std::isfinite(hit.u) && std::isfinite(hit.v)) << name;
            EXPECT_GE(hit.u, -0.5);
            EXPECT_LT(hit.u, W - 0.5);
            OpticsRay ray;
            ASSERT_TRUE(chief_ray_through(m, W, H, hit.u + 0.5, hit.v + 0.5, &hit.lens, &ray)) << name;
            const Vec3 x{point[0], point[1], point[2]};
            const double miss = test::distance_to_line(x, origin_of(ray), dir_of(ray));
            // A thin microlens that the point's cone of light covers only in part images it at
            // the centroid of that part, off the line through the lens centre
            // (ForwardProjectionIsTheCentroidOfTheLightThroughEachLens checks those hits).
            if (partly_covered(m, x, hit.lens))
                continue;
            EXPECT_LT(miss, 1e-7 * z) << name << ": point " << str(x) << " lens (" << hit.lens.k << ","
                                      << hit.lens.l << ") at (" << hit.u << ", " << hit.v << ") chief ray misses by "
                                      << miss << " mm";
            // The hit lies in that lens's microimage cell.
            LensIndex owner;
            ASSERT_TRUE(own_lens(m, sensor_point(m, W, H, hit.u + 0.5, hit.v + 0.5), &owner));
            EXPECT_EQ(owner, hit.lens) << name;
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
    const Model m = make_model(params);
    const int W = 401, H = 301;
    const double F = m.focal_length_mm, D = m.distance_mm, r = 0.5 * m.aperture_mm;
    const double d = m.array_distance_mm, sx = m.pixel_size_mm[0], sy = m.pixel_size_mm[1];
    int compared = 0;
    const double xs[][3] = {{3, -2, 400}, {-10, 6, 900}, {20, 12, 1500}, {0.4, -0.3, F * D / (D - F) * 1.02}};
    for (const auto& p : xs) {
        const std::vector<PixelHit> hits = forward_project(m, W, H, p);
        std::map<std::pair<long long, long long>, std::array<double, 3>> sums;  // u, v, count
        std::mt19937_64 rng(11);
        std::uniform_real_distribution<double> uni(0, 1);
        for (int n = 0; n < 400000; ++n) {
            const double rho = r * std::sqrt(uni(rng)), phi = 2 * 3.14159265358979323846 * uni(rng);
            const double mx = rho * std::cos(phi), my = rho * std::sin(phi);
            // Slope (per unit +z) of the ray X -> aperture point, then undo the main lens.
            const double wx = (p[0] - mx) / p[2] + mx / F, wy = (p[1] - my) / p[2] + my / F;
            const double hx = mx - wx * D, hy = my - wy * D;
            const LensIndex lens = test::brute_force_nearest(m.grid, m.pitch_mm, hx, hy);
            const Vec2 c = lens_centre(m.grid, m.pitch_mm, lens);
            const double f = m.microlens_focal_mm[lens_type(lens, m.lens_type_count)];
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
    const Model m = make_model(thin_lens_camera(50, 4, 52));
    const int W = 640, H = 480;
    const double point[3] = {100, -50, 2000};
    const std::vector<PixelHit> hits = forward_project(m, W, H, point);
    ASSERT_EQ(hits.size(), 1u);
    // Inverted on the sensor: x = -100 * 52 / 2000 = -2.6 mm, y = +1.3 mm; read out upright:
    // right of the axis -> right of the image (u = 319.5 + 260), below -> below (v = 239.5 + 130).
    EXPECT_NEAR(hits[0].u, 319.5 + 2.6 / 0.01, 1e-9);
    EXPECT_NEAR(hits[0].v, 239.5 + 1.3 / 0.01, 1e-9);
    const double behind[3] = {0, 0, -10};
    EXPECT_TRUE(forward_project(m, W, H, behind).empty());
}

// ---------------------------------------------------------------- microimage lattice

void check_lftoolbox(GridType grid, double rotate_z, double offset_x, double tx)
{
    CameraParams params = plenoptic_camera(grid, 0.137, 0.7, 0.7, 50, 5, 52);
    test::set_pose(&params, 0, 0, rotate_z, tx, -0.011, 0);
    params.sensor.offset_mm[0] = offset_x;
    ASSERT_EQ(check_camera(params), "");
    const Model m = make_model(params);
    const int W = 320, H = 240;
    const MicroimageLattice lattice = microimage_lattice(m, W, H);
    ASSERT_TRUE(lattice.valid);
    ASSERT_TRUE(lattice.lftoolbox_valid);
    EXPECT_TRUE(lattice.exact);
    // The optics -> pixel map mirrors x, so a rotation theta appears as -theta.
    EXPECT_NEAR(lattice.rot, -rotate_z * test::kPi / 180, 1e-9) << "rotate " << rotate_z;
    if (grid == GridType::Hexagonal)
        EXPECT_TRUE(lattice.first_pos_shift_row == 1 || lattice.first_pos_shift_row == 2);
    else
        EXPECT_EQ(lattice.first_pos_shift_row, 0);
    ASSERT_GT(lattice.u_max, 5);
    ASSERT_GT(lattice.v_max, 5);

    // LFToolbox's normalisation: the origin's projections on the rotated axes lie in
    // [0, HSpacing/2) x [0, VSpacing).
    const double c = std::cos(lattice.rot), s = std::sin(lattice.rot);
    const double h_proj = c * lattice.h_offset + s * lattice.v_offset;
    const double v_proj = -s * lattice.h_offset + c * lattice.v_offset;
    EXPECT_GE(h_proj, -1e-9);
    EXPECT_LT(h_proj, (grid == GridType::Hexagonal ? 0.5 : 1.0) * lattice.h_spacing);
    EXPECT_GE(v_proj, -1e-9);
    EXPECT_LT(v_proj, lattice.v_spacing);
    EXPECT_EQ(lattice.u_max, (long long)std::floor((W - lattice.h_offset) / lattice.h_spacing) + 1);
    EXPECT_EQ(lattice.v_max, (long long)std::floor((H - lattice.v_offset) / lattice.v_spacing) + 1);

    // Rebuild LFToolbox's grid and compare every grid point with the true microimage centre.
    int covered = 0;
    for (long long row = 0; row < lattice.v_max; ++row) {
        for (long long col = 0; col < lattice.u_max; ++col) {
            double uu = col * lattice.h_spacing, vv = row * lattice.v_spacing;
            if (lattice.first_pos_shift_row > 0 && (row + 1) >= lattice.first_pos_shift_row &&
                ((row + 1 - lattice.first_pos_shift_row) % 2 == 0))
                uu += lattice.h_spacing / 2;
            const double x = c * uu - s * vv + lattice.h_offset;  // 1-based
            const double y = s * uu + c * vv + lattice.v_offset;
            const double u = x - 1, v = y - 1;
            LensIndex lens;
            ASSERT_TRUE(own_lens(m, sensor_point(m, W, H, u + 0.5, v + 0.5), &lens));
            double cu, cv;
            ASSERT_TRUE(microimage_centre_px(m, W, H, lens, &cu, &cv));
            EXPECT_NEAR(cu, u, 1e-6) << "grid (" << row << "," << col << ") rotate " << rotate_z;
            EXPECT_NEAR(cv, v, 1e-6) << "grid (" << row << "," << col << ") rotate " << rotate_z;
            if (u >= -0.5 && u <= W - 1 && v >= -0.5 && v <= H - 1)
                ++covered;
            if (row == 0 && col == 0) {
                EXPECT_EQ(lens, lattice.first_lens);
            }
        }
    }
    // The basis of the microimage lattice matches neighbouring lenses' centres.
    double u0, v0, u1, v1;
    ASSERT_TRUE(microimage_centre_px(m, W, H, from_skew(grid, 3, -2), &u0, &v0));
    ASSERT_TRUE(microimage_centre_px(m, W, H, from_skew(grid, 4, -1), &u1, &v1));
    EXPECT_NEAR(u1 - u0, lattice.basis_a_px[0] + lattice.basis_b_px[0], 1e-6);
    EXPECT_NEAR(v1 - v0, lattice.basis_a_px[1] + lattice.basis_b_px[1], 1e-6);

    if (rotate_z == 0) {
        // Unrotated, every microimage centre in the image (up to LFToolbox's last pixel centre,
        // W and H 1-based) is on the grid: count them directly.
        int expected = 0;
        for (int l = -200; l <= 200; ++l) {
            for (int k = -200; k <= 200; ++k) {
                double u, v;
                microimage_centre_px(m, W, H, LensIndex{k, l}, &u, &v);
                if (u >= -0.5 && u <= W - 1 && v >= -0.5 && v <= H - 1)
                    ++expected;
            }
        }
        EXPECT_EQ(covered, expected);
    }
}

TEST(Optics, LftoolboxGridRebuildsTheMicroimageCentres)
{
    for (double rotate_z : {0.0, 0.5, -3.0, 12.0, -28.0})
        check_lftoolbox(GridType::Hexagonal, rotate_z, 0.013, 0.004);
    check_lftoolbox(GridType::Hexagonal, 0, 0, 0);
    check_lftoolbox(GridType::Rectangular, 0, 0.02, 0);
    check_lftoolbox(GridType::Rectangular, 4, 0, 0.01);
}

TEST(Optics, TiltedArrayLatticeIsMarkedApproximate)
{
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 0.137, 0.7, 0.7, 50, 5, 52);
    test::set_pose(&params, 1, 0, 0, 0, 0, 0);
    const Model m = make_model(params);
    const MicroimageLattice lattice = microimage_lattice(m, 320, 240);
    ASSERT_TRUE(lattice.valid);
    EXPECT_FALSE(lattice.exact);
    // Still a tenth of a pixel near the centre.
    double u0, v0, u1, v1;
    ASSERT_TRUE(microimage_centre_px(m, 320, 240, LensIndex{0, 0}, &u0, &v0));
    ASSERT_TRUE(microimage_centre_px(m, 320, 240, LensIndex{1, 0}, &u1, &v1));
    EXPECT_NEAR(u1 - u0, lattice.basis_a_px[0], 0.1);
    EXPECT_NEAR(v1 - v0, lattice.basis_a_px[1], 0.1);
}

TEST(Optics, MicroimageCentreIsTheCentralProjectionOfTheLensCentre)
{
    // The chief ray from a microimage centre through its pinhole lens passes through the main-lens
    // centre.
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 0.3, 0, 2, 50, 4, 52);
    test::set_pose(&params, 2, -1, 7, 0.02, 0.01, -0.1);
    const Model m = make_model(params);
    const int W = 300, H = 300;
    for (int k = -4; k <= 4; ++k) {
        const LensIndex lens{k, k / 2};
        double u, v;
        ASSERT_TRUE(microimage_centre_px(m, W, H, lens, &u, &v));
        OpticsRay ray;
        ASSERT_TRUE(chief_ray_through(m, W, H, u + 0.5, v + 0.5, &lens, &ray));
        EXPECT_LT(length(origin_of(ray)), 1e-9) << "lens " << k << " origin " << str(origin_of(ray));
    }
}

// Brute force: every lens within the rings that delivers light to some sample of a pixel must be
// in the pixel's overlap list, and the list should be much shorter than all candidates.
void check_overlap_pruning(const char* name, CameraParams params, double max_kept_fraction)
{
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
    ASSERT_EQ(check_camera(params), "") << name;
    const Model m = make_model(params);
    ASSERT_TRUE(m.model_overlap) << name;
    const int W = 160, H = 120, R = m.overlap_rings;
    LensIndex lenses[kMaxOverlapLenses];
    long long kept = 0, candidates = 0, lit_total = 0;
    int failures = 0;
    for (int j = 1; j < H && failures < 5; j += 5) {
        for (int i = 2; i < W && failures < 5; i += 4) {
            const int count = overlap_lenses(m, W, H, i, j, lenses, kMaxOverlapLenses);
            ASSERT_GE(count, 1) << name;
            kept += count;
            const LensIndex own = lenses[0];
            const std::int64_t own_skew = skew_k(m.grid, own);
            for (int dl = -R - 1; dl <= R + 1; ++dl) {
                for (int dk = -R - 1; dk <= R + 1; ++dk) {
                    const LensIndex lens = from_skew(m.grid, own_skew + dk, own.l + dl);
                    const bool in_rings = m.grid == GridType::Hexagonal
                                              ? std::max(std::abs(dk), std::max(std::abs(dl), std::abs(dk + dl))) <= R
                                              : std::max(std::abs(dk), std::abs(dl)) <= R;
                    if (in_rings)
                        ++candidates;
                    bool lit = false;
                    for (int n = 0; n < 48 && !lit; ++n) {
                        OpticsRay ray;
                        lit = generate_ray(m, W, H, i, j, make_sample(i, j, n, 48), &lens, &ray);
                    }
                    if (!lit)
                        continue;
                    ++lit_total;
                    bool listed = false;
                    for (int s = 0; s < count; ++s)
                        listed = listed || lenses[s] == lens;
                    if (!listed) {
                        ++failures;
                        ADD_FAILURE() << name << ": pixel " << i << "," << j << " receives light through lens ("
                                      << lens.k << "," << lens.l << "), offset " << dk << "," << dl
                                      << ", which its overlap list (" << count << " lenses, " << R
                                      << " rings) leaves out";
                    }
                }
            }
        }
    }
    EXPECT_GT(lit_total, 0) << name;
    ::testing::Test::RecordProperty(std::string("overlap_lenses_kept_") + name, std::to_string(kept) + " of " + std::to_string(candidates));
    EXPECT_LT(double(kept), max_kept_fraction * double(candidates))
        << name << ": pruning keeps " << kept << " of " << candidates << " candidate lenses";
}

TEST(Optics, OverlapPruningNeverDropsALensThatDeliversLight)
{
    check_overlap_pruning("plenoptic 1.0 at f/2.5", plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 2.5, 50), 0.5);
    check_overlap_pruning("matched plenoptic 1.0", plenoptic_camera(GridType::Rectangular, 0.1, 0.5, 0.5, 50, 5, 50), 0.3);
    check_overlap_pruning("focused 2.0 at f/2", plenoptic_camera(GridType::Hexagonal, 0.2, 1.5, 2.0, 50, 2, 55), 0.5);
    check_overlap_pruning("pinhole array at f/2", plenoptic_camera(GridType::Rectangular, 0.2, 0, 2.0, 50, 2, 55), 0.5);
    CameraParams slight = plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 2.5, 50);
    test::set_pose(&slight, 0.5, -0.3, 5, 0.01, 0, 0.02);
    check_overlap_pruning("plenoptic 1.0 tilted 0.5 degrees", slight, 0.5);
    CameraParams tilted = plenoptic_camera(GridType::Hexagonal, 0.2, 1.5, 2.0, 50, 2, 55);
    test::set_pose(&tilted, 3, 2, 0, 0, 0.02, 0);
    check_overlap_pruning("focused 2.0 tilted 3.6 degrees", tilted, 0.6);
    CameraParams steep = plenoptic_camera(GridType::Rectangular, 0.1, 0.5, 0.5, 50, 2.5, 50);
    test::set_pose(&steep, 8, -7, 20, 0, 0, 0);  // about 10.6 degrees, just inside the pruned range
    check_overlap_pruning("plenoptic 1.0 tilted 10.6 degrees", steep, 0.6);
    CameraParams pinhole_main;
    pinhole_main.main.given = true;
    pinhole_main.main.type = MainLensType::Pinhole;
    pinhole_main.main.has_distance = true;
    pinhole_main.main.distance_mm = 55;
    test::add_array(&pinhole_main, GridType::Hexagonal, 0.2, 0.5, 2.0);
    check_overlap_pruning("pinhole main lens, strong microlenses", pinhole_main, 0.6);
}

TEST(Optics, OverlapLensesListsTheOwnLensFirst)
{
    const int W = 200, H = 200;
    const Model apart = make_model(plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 10, 50));
    LensIndex lenses[kMaxOverlapLenses];
    EXPECT_EQ(overlap_lenses(apart, W, H, 10, 20, lenses, kMaxOverlapLenses), 1);
    LensIndex own;
    ASSERT_TRUE(own_lens(apart, sensor_point(apart, W, H, 10.5, 20.5), &own));
    EXPECT_EQ(lenses[0], own);

    const Model overlapping = make_model(plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 2.5, 50));
    int most = 0;
    for (int j = 0; j < H; j += 3)
        for (int i = 0; i < W; i += 3)
            most = std::max(most, overlap_lenses(overlapping, W, H, i, j, lenses, kMaxOverlapLenses));
    EXPECT_GE(most, 3) << "a main lens at half the matched f-number lights pixels through several lenses";
    EXPECT_LE(most, kMaxOverlapLenses);
}

} // namespace
} // namespace plenoptic
