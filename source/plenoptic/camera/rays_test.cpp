// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the rays: axis, conjugates, lookup through the pose, round trips, overlap lenses.

#include <cmath>
#include <array>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/camera/aim.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/core/test_util.h"

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
    const PlenopticCamera m = make_camera(p);
    const int W = 640, H = 480;
    // Pixel (i, j)'s centre: x = -((i + 0.5) - W/2) sx + ox, y = ((j + 0.5) - H/2) sy + oy.
    const Vec3 c = with_film(m, W, H).sensor.point(10 + 0.5, 20 + 0.5);
    EXPECT_DOUBLE_EQ(c.x, -((10 + 0.5) - 320) * 0.01 + 0.3);
    EXPECT_DOUBLE_EQ(c.y, ((20 + 0.5) - 240) * 0.02 - 0.1);
    EXPECT_DOUBLE_EQ(c.z, -52);
    const PixelPoint px = with_film(m, W, H).sensor.to_pixel(c.x, c.y);
    EXPECT_TRUE(px.inside);
    const double u = px.u, v = px.v;
    EXPECT_NEAR(u, 10, 1e-9);
    EXPECT_NEAR(v, 20, 1e-9);
    const Vec2 principal = with_film(m, W, H).sensor.principal_point_px();
    EXPECT_NEAR(principal.x, 319.5 + 30, 1e-9);
    EXPECT_NEAR(principal.y, 239.5 + 5, 1e-9);
}

void expect_axis(const OpticsRay& ray, const char* what)
{
    EXPECT_NEAR(ray.origin_mm.x, 0, 1e-15) << what;
    EXPECT_NEAR(ray.origin_mm.y, 0, 1e-15) << what;
    EXPECT_NEAR(ray.origin_mm.z, 0, 1e-15) << what;
    EXPECT_NEAR(ray.dir.x, 0, 1e-15) << what << " direction " << str(dir_of(ray));
    EXPECT_NEAR(ray.dir.y, 0, 1e-15) << what << " direction " << str(dir_of(ray));
    EXPECT_NEAR(ray.dir.z, 1, 1e-15) << what << " direction " << str(dir_of(ray));
}

TEST(Optics, CentreSampleGivesTheOpticalAxis)
{
    const int W = 101, H = 101;  // pixel (50, 50) is centred on the axis
    OpticsRay ray;
    ASSERT_TRUE((ray = generate_ray(with_film(make_camera(thin_lens_camera(50, 4, 52)), W, H), 50, 50, kCentreSample, nullptr)).passed);
    expect_axis(ray, "thin lens, no array");

    for (GridType grid : {GridType::Hexagonal, GridType::Rectangular}) {
        ASSERT_TRUE((ray = generate_ray(with_film(make_camera(plenoptic_camera(grid, 0.5, 2, 2, 50, 4, 52)), W, H), 50, 50, kCentreSample, nullptr)).passed);
        expect_axis(ray, "plenoptic 1.0");
        ASSERT_TRUE((ray = generate_ray(with_film(make_camera(plenoptic_camera(grid, 0.5, 0, 2, 50, 4, 52)), W, H), 50, 50, kCentreSample, nullptr)).passed);
        expect_axis(ray, "pinhole array");
    }
    CameraParams pinhole_main;
    pinhole_main.main.given = true;
    pinhole_main.main.type = MainLensType::Pinhole;
    pinhole_main.main.has_distance = true;
    pinhole_main.main.distance_mm = 52;
    test::add_array(&pinhole_main, GridType::Hexagonal, 0.5, 1.5, 2);
    ASSERT_EQ(check_camera(pinhole_main), "");
    ASSERT_TRUE((ray = with_film(make_camera(pinhole_main), W, H).generate_ray(50, 50, kCentreSample)).passed);
    expect_axis(ray, "pinhole main lens, thin array");
}

// ---------------------------------------------------------------- conjugates

TEST(Optics, RaysFromASensorPointMeetAtTheThinLensConjugate)
{
    const double F = 50, D = 60;
    const PlenopticCamera m = make_camera(thin_lens_camera(F, 2.8, D));
    const int W = 101, H = 101, i = 10, j = 80;
    const Vec3 p = with_film(m, W, H).sensor.point(i + 0.5, j + 0.5);
    // Independently: 1/u = 1/F - 1/D, lateral magnification -u/D.
    const double u = 1 / (1 / F - 1 / D);
    const Vec3 conjugate{-p.x * u / D, -p.y * u / D, u};
    double spread = 0;
    for (int n = 0; n < 200; ++n) {
        CameraSample s = make_sample(i, j, n, 200);
        s.pixel_u = s.pixel_v = 0.5;  // one sensor point, many lens points
        OpticsRay ray;
        ASSERT_TRUE((ray = with_film(m, W, H).generate_ray(i, j, s)).passed);
        const double miss = test::distance_to_line(conjugate, origin_of(ray), dir_of(ray));
        EXPECT_LT(miss, 1e-9 * u) << "sample " << n << " origin " << str(origin_of(ray)) << " misses "
                                  << str(conjugate) << " by " << miss;
        spread = std::max(spread, length(origin_of(ray)));
    }
    EXPECT_GT(spread, 0.4 * m.aperture_mm() / 2);  // the rays really cover the aperture
}

TEST(Optics, SensorAtTheFocalPlaneGivesParallelRays)
{
    const double F = 50;
    const PlenopticCamera m = make_camera(thin_lens_camera(F, 2.8, F));  // D = F exactly
    const int W = 101, H = 101, i = 3, j = 77;
    const Vec3 p = with_film(m, W, H).sensor.point(i + 0.5, j + 0.5);
    const Vec3 expected = normalized(-p);
    for (int n = 0; n < 100; ++n) {
        CameraSample s = make_sample(i, j, n, 100);
        s.pixel_u = s.pixel_v = 0.5;
        OpticsRay ray;
        ASSERT_TRUE((ray = with_film(m, W, H).generate_ray(i, j, s)).passed);
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
    const PlenopticCamera m = make_camera(params);
    const int W = 200, H = 200, i = 120, j = 61;
    const Vec3 p = with_film(m, W, H).sensor.point(i + 0.5, j + 0.5);
    // Lens and distances in the array's frame, computed here with the reference rotation.
    const Vec3 centre = m.array.pose.centre_mm;
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
        ASSERT_TRUE((ray = with_film(m, W, H).generate_ray(i, j, s)).passed);
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
    const PlenopticCamera m = make_camera(params);
    const Vec3 centre = m.array.pose.centre_mm;
    const Vec3 n = test::reference_rotate(deg, Vec3{0, 0, 1});
    std::mt19937_64 rng(2024);
    std::uniform_real_distribution<double> coordinate(-5.0, 5.0);
    int failures = 0;
    for (int k = 0; k < 100000 && failures < 5; ++k) {
        const Vec3 p{coordinate(rng), coordinate(rng), m.sensor.z_mm};
        Vec3 q;
        if (with_main_lens)
            q = (dot(n, centre) / dot(n, p)) * p;  // line from the main-lens centre
        else
            q = p + Vec3{0, 0, dot(n, centre - p) / n.z};  // straight up
        const Vec3 local = test::reference_unrotate(deg, q - centre);
        const LensIndex expected = test::brute_force_nearest(grid, 0.13, local.x, local.y);
        const OwnLens found_lookup = own_lens(m, p);
        ASSERT_TRUE(found_lookup.found);
        const LensIndex found = found_lookup.lens;
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
Vec3 trace_back(const PlenopticCamera& m, const CameraParams& params, const OpticsRay& ray, std::string* failure)
{
    const double* deg = params.array.rotate_deg;
    Vec3 at = origin_of(ray);
    Vec3 back;  // direction of travel towards the sensor, unit z magnitude where relevant
    const Vec3 d = dir_of(ray);
    if (test::lens_kind(m) == "thin_lens") {
        // Undo w' = w - m/F at the main lens.
        back = -Vec3{d.x / d.z + at.x / m.focal_length_mm(), d.y / d.z + at.y / m.focal_length_mm(), 1};
    } else {
        back = -d;
    }
    if (m.array.grid == GridType::None) {
        const double t = (m.sensor.z_mm - at.z) / back.z;
        return at + t * back;
    }
    // Meet the posed array plane.
    const Vec3 centre{params.array.translate_mm[0], params.array.translate_mm[1],
                      (test::lens_kind(m) == "none" ? 0 : -m.distance_mm) + params.array.translate_mm[2]};
    const Vec3 n = test::reference_rotate(deg, Vec3{0, 0, 1});
    if (test::lens_kind(m) != "none") {
        const double t = dot(n, centre - at) / dot(n, back);
        at = at + t * back;
    }
    const Vec3 h_local = test::reference_unrotate(deg, at - centre);
    const LensIndex lens = test::brute_force_nearest(m.array.grid, m.array.pitch_mm, h_local.x, h_local.y);
    const Vec2 c = lens_centre(m.array.grid, m.array.pitch_mm, lens);
    Vec3 w = test::reference_unrotate(deg, back);
    w = (1 / -w.z) * w;  // unit travel along -z_local
    if (params.array.lens == MicrolensType::ThinLens) {
        // Type rule written out here: skew k = k - floor(l/2), type = (k_s - l) mod 3.
        int type = 0;
        if (params.array.focal_length_count == 3) {
            const long long l = lens.l, ks = lens.k - (l >= 0 ? l / 2 : -((-l + 1) / 2));
            type = int((((ks - l) % 3) + 3) % 3);
        }
        const double f = params.array.focal_lengths_mm[type];
        // Undo the microlens: sensor-side slope = scene-side slope - (h - c)/f for this direction.
        w = Vec3{w.x - (h_local.x - c.x) / f, w.y - (h_local.y - c.y) / f, -1};
    } else if (std::hypot(h_local.x - c.x, h_local.y - c.y) > 1e-9) {
        *failure = "ray does not pass the pinhole's centre";
    }
    const Vec3 down = test::reference_rotate(deg, w);
    const double t = (m.sensor.z_mm - at.z) / down.z;
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
        const PlenopticCamera m = with_film(make_camera(c.params), W, H);
        int traced = 0;
        double worst = 0;
        for (int j = 0; j < H; j += 7) {
            for (int i = 0; i < W; i += 5) {
                for (int n = 0; n < 8; ++n) {
                    const CameraSample s = make_sample(i, j, n, 8);
                    OpticsRay ray;
                    if (!(ray = m.generate_ray(i, j, s)).passed)
                        continue;
                    std::string failure;
                    const Vec3 back = trace_back(m, c.params, ray, &failure);
                    const Vec3 start = m.sensor.point(i + s.pixel_u, j + s.pixel_v);
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

// Brute force: every lens within the rings that delivers light to some sample of a pixel must be
// in the pixel's overlap list, and the list should be much shorter than all candidates.
void check_overlap_pruning(const char* name, CameraParams params, double max_kept_fraction)
{
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
    ASSERT_EQ(check_camera(params), "") << name;
    const PlenopticCamera m = make_camera(params);
    ASSERT_TRUE(m.overlap.modelled) << name;
    const int W = 160, H = 120, R = m.overlap.rings;
    LensIndex lenses[kMaxOverlapLenses];
    long long kept = 0, candidates = 0, lit_total = 0;
    int failures = 0;
    for (int j = 1; j < H && failures < 5; j += 5) {
        for (int i = 2; i < W && failures < 5; i += 4) {
            const int count = overlap_lenses(with_film(m, W, H), i, j, lenses, kMaxOverlapLenses);
            ASSERT_GE(count, 1) << name;
            kept += count;
            const LensIndex own = lenses[0];
            const std::int64_t own_skew = skew_k(m.array.grid, own);
            for (int dl = -R - 1; dl <= R + 1; ++dl) {
                for (int dk = -R - 1; dk <= R + 1; ++dk) {
                    const LensIndex lens = from_skew(m.array.grid, own_skew + dk, own.l + dl);
                    const bool in_rings = m.array.grid == GridType::Hexagonal
                                              ? std::max(std::abs(dk), std::max(std::abs(dl), std::abs(dk + dl))) <= R
                                              : std::max(std::abs(dk), std::abs(dl)) <= R;
                    if (in_rings)
                        ++candidates;
                    bool lit = false;
                    for (int n = 0; n < 48 && !lit; ++n) {
                        OpticsRay ray;
                        lit = (ray = generate_ray(with_film(m, W, H), i, j, make_sample(i, j, n, 48), &lens)).passed;
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
    // Manufacturing errors: displaced, tilted lenses of scattered focal lengths, and clear gaps.
    CameraParams jittered = plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 2.5, 50);
    jittered.array.has_errors = true;
    jittered.array.errors.position_sd_mm = 0.004;
    jittered.array.errors.position_sd_z_mm = 0.003;
    jittered.array.errors.focal_sd = 0.04;
    jittered.array.errors.rotation_deg = 5;
    jittered.array.errors.seed = 11;
    check_overlap_pruning("plenoptic 1.0 with errors", jittered, 0.6);
    CameraParams focused_errors = plenoptic_camera(GridType::Rectangular, 0.2, 1.5, 2.0, 50, 2, 55);
    focused_errors.array.has_errors = true;
    focused_errors.array.errors.position_sd_mm = 0.006;
    focused_errors.array.errors.focal_sd = 0.03;
    focused_errors.array.errors.rotation_deg = 2;
    check_overlap_pruning("focused 2.0 with errors", focused_errors, 0.6);
    CameraParams clear_gap = plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 5, 50);
    clear_gap.array.fill_factor = 0.6;
    check_overlap_pruning("matched plenoptic 1.0 with clear gaps", clear_gap, 0.8);
    // Behind a traced lens (pupil bounds decide), lenses displaced along the normal and tilted.
    const Prescription triplet = test::vignetting_triplet();
    CameraParams real = plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 4, paraxial_image_distance(triplet, 3000).mm);
    test::use_prescription(&real, triplet);
    real.array.has_errors = true;
    real.array.errors.position_sd_mm = 0.004;
    real.array.errors.position_sd_z_mm = 0.005;
    real.array.errors.focal_sd = 0.03;
    real.array.errors.rotation_deg = 4;
    check_overlap_pruning("traced triplet, lenses with errors", real, 0.8);
    // Refracting caps on a thick substrate (light crosses into the neighbours' glass), either side
    // facing the main lens, and with errors: the rings and the pruning come from the traced reach.
    // The point here is that no lens that delivers light is dropped; how many candidates the
    // pruning keeps is not asserted (with tilted lenses, by the reach of the centre lens tilted
    // every way: traced_reach_mm).
    for (bool scene_side : {true, false}) {
        CameraParams refracting = plenoptic_camera(GridType::Hexagonal, 0.1, 0.16, 0.2, 50, 2.5, 50);
        test::use_refracting_caps(&refracting, 0.08, 1.5, 0.025, 0.2);
        refracting.array.refracting.curved_towards_scene = scene_side;
        const std::string name = std::string("refracting caps towards the ") + (scene_side ? "scene" : "sensor");
        check_overlap_pruning(name.c_str(), refracting, 1.01);
        if (!scene_side) {
            refracting.array.has_errors = true;
            refracting.array.errors.position_sd_mm = 0.003;
            refracting.array.errors.focal_sd = 0.03;
            refracting.array.errors.rotation_deg = 2;
            refracting.array.errors.seed = 5;
            check_overlap_pruning((name + ", errors").c_str(), refracting, 1.01);
            // Without tilts the traced reach prunes: displaced lenses of scattered focal lengths.
            refracting.array.errors.rotation_deg = 0;
            refracting.array.errors.focal_sd = 0.04;
            check_overlap_pruning((name + ", errors without tilts").c_str(), refracting, 1.01);
        }
    }
}

// With aimed samples a pixel leaves out the overlap lenses whose aim finds no part of it where their
// light lands (aim_reaches_pixel, camera/pixel.h). Checked by brute force: through every lens left
// out, 256 uniform samples of the pixel and the cell (the renderer's unaimed rays, forced through
// that lens) all miss; and the test is not empty: lenses are left out, and lenses kept are lit.
void check_aim_leaves_out_only_dark_lenses(const char* name, CameraParams params)
{
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
    ASSERT_EQ(check_camera(params), "") << name;
    const PlenopticCamera m = with_film(make_camera(params), 160, 120);
    ASSERT_TRUE(m.overlap.modelled) << name;
    ASSERT_TRUE(m.sampling.aim) << name;
    LensIndex lenses[kMaxOverlapLenses];
    int left_out = 0, kept_lit = 0, failures = 0;
    for (int j = 1; j < 120 && failures < 5; j += 7) {
        for (int i = 2; i < 160 && failures < 5; i += 6) {
            const int count = overlap_lenses(m, i, j, lenses, kMaxOverlapLenses);
            for (int s = 0; s < count; ++s) {
                bool lit = false;
                for (int n = 0; n < 256 && !lit; ++n)
                    lit = generate_ray_unaimed(m, i, j, make_sample(i, j, n, 256), &lenses[s]).passed;
                if (aim_reaches_pixel(m, i, j, lenses[s])) {
                    kept_lit += lit;
                    continue;
                }
                ++left_out;
                if (lit) {
                    ++failures;
                    ADD_FAILURE() << name << ": pixel " << i << "," << j << " receives light through lens ("
                                  << lenses[s].k << "," << lenses[s].l << "), which its aim says cannot reach it";
                }
            }
        }
    }
    EXPECT_GT(left_out, 0) << name;
    EXPECT_GT(kept_lit, 0) << name;
}

TEST(Optics, AimLeavesOutOnlyOverlapLensesThatCannotLightThePixel)
{
    check_aim_leaves_out_only_dark_lenses("matched plenoptic 1.0", plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 5, 50));
    check_aim_leaves_out_only_dark_lenses("plenoptic 1.0 at f/2.5", plenoptic_camera(GridType::Rectangular, 0.1, 0.5, 0.5, 50, 2.5, 50));
    const Prescription triplet = test::vignetting_triplet();
    CameraParams real = plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 4, paraxial_image_distance(triplet, 3000).mm);
    test::use_prescription(&real, triplet);
    check_aim_leaves_out_only_dark_lenses("traced triplet", real);
    real.array.has_errors = true;
    real.array.errors.position_sd_mm = 0.004;
    real.array.errors.focal_sd = 0.03;
    real.array.errors.seed = 7;
    check_aim_leaves_out_only_dark_lenses("traced triplet, lenses with errors", real);
}

TEST(Optics, OverlapLensesListsTheOwnLensFirst)
{
    const int W = 200, H = 200;
    const PlenopticCamera apart = with_film(make_camera(plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 10, 50)), W, H);
    LensIndex lenses[kMaxOverlapLenses];
    EXPECT_EQ(overlap_lenses(apart, 10, 20, lenses, kMaxOverlapLenses), 1);
    const OwnLens own_lookup = own_lens(apart, apart.sensor.point(10.5, 20.5));
    ASSERT_TRUE(own_lookup.found);
    const LensIndex own = own_lookup.lens;
    EXPECT_EQ(lenses[0], own);

    const PlenopticCamera overlapping = with_film(make_camera(plenoptic_camera(GridType::Hexagonal, 0.1, 0.5, 0.5, 50, 2.5, 50)), W, H);
    int most = 0;
    for (int j = 0; j < H; j += 3)
        for (int i = 0; i < W; i += 3)
            most = std::max(most, overlap_lenses(overlapping, i, j, lenses, kMaxOverlapLenses));
    EXPECT_GE(most, 3) << "a main lens at half the matched f-number lights pixels through several lenses";
    EXPECT_LE(most, kMaxOverlapLenses);
}

} // namespace
} // namespace plenoptic
