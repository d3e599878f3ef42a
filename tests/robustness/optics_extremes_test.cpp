// SPDX-License-Identifier: AGPL-3.0-or-later
// The optics at the extremes, beyond source/plenoptic/camera/stress_test.cpp (which checks finite
// unit directions for a list of singular-looking cases): here every unblocked ray must also start on
// the plane of the last element it leaves (and inside its aperture), and the rays of one sensor
// point must meet at its conjugate wherever one exists, computed independently with the thin-lens
// equation, at focal lengths from 1e-6 mm to 1e6 mm, at and within 1e-12 of d = f and D = F, and for
// arrays tilted up to 89.99 degrees. A sweep over a grid of extreme values checks the invariants on
// every accepted parameter set.

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/optics.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/core/sampling.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::dir_of;
using test::origin_of;
using test::str;

std::string describe(const CameraParams& p)
{
    std::ostringstream out;
    out.precision(17);
    out << "main " << (p.main.given ? (p.main.type == MainLensType::Pinhole ? "pinhole" : "thin") : "none");
    if (p.main.given)
        out << " F=" << p.main.focal_length_mm << " N=" << p.main.f_number << " D=" << p.main.distance_mm;
    out << ", array " << (p.array.given ? (p.array.grid == GridType::Hexagonal ? "hex" : "rect") : "none");
    if (p.array.given)
        out << " p=" << p.array.pitch_mm << " f=" << (p.array.focal_length_count ? p.array.focal_lengths_mm[0] : 0)
            << " d=" << p.array.distance_mm << " rot=<" << p.array.rotate_deg[0] << "," << p.array.rotate_deg[1]
            << "," << p.array.rotate_deg[2] << ">";
    out << ", pixel " << p.sensor.pixel_size_mm[0];
    return out.str();
}

// Distance from X to the whole line through the ray (conjugates may be virtual: behind the origin).
double miss(Vec3 x, const OpticsRay& ray)
{
    return test::distance_to_line(x, origin_of(ray), dir_of(ray));
}

CameraParams thin_main(double F, double N, double D)
{
    return test::thin_lens_camera(F, N, D);
}

CameraParams pinhole_main(double D)
{
    CameraParams p;
    p.main.given = true;
    p.main.type = MainLensType::Pinhole;
    p.main.has_distance = true;
    p.main.distance_mm = D;
    return p;
}

// Rays of one sensor point: pixel (i, j)'s centre, `count` aperture samples. Unblocked ones only.
std::vector<OpticsRay> rays_of_point(const PlenopticCamera& m, int i, int j, int count)
{
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    std::vector<OpticsRay> rays;
    for (int n = 0; n < count; ++n) {
        CameraSample s = make_sample(i, j, n, count);
        s.pixel_u = s.pixel_v = 0.5;
        OpticsRay ray;
        if ((ray = with_film(m, W, H).generate_ray(i, j, s)).passed)
            rays.push_back(ray);
    }
    return rays;
}

// ------------------------------------------------------------------ thin main lens, no array

TEST(OpticsExtremes, ThinMainLensRaysMeetAtTheConjugateFromFocalLength1e6To1e_6)
{
    const int W = 21, H = 15, i = 3, j = 12;
    for (double F : {1e-6, 1e-3, 1.0, 50.0, 1e3, 1e6}) {
        // u = F D / (D - F): unit magnification, a far conjugate, and one a hair from infinity.
        for (double D_over_F : {2.0, 1.5, 1 + 1e-6, 1 + 1e-12}) {
            const double D = F * D_over_F;
            CameraParams params = thin_main(F, 2.8, D);
            params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = F * 1e-3;  // ~0.01 rad per pixel
            ASSERT_EQ(check_camera(params), "") << describe(params);
            const PlenopticCamera m = with_film(make_camera(params), W, H);
            const Vec3 p = m.sensor.point(i + 0.5, j + 0.5);
            // Independently, with divisions (the code under test has none): the image of p.
            const double u = 1 / (1 / F - 1 / m.distance_mm);
            const Vec3 conjugate{-p.x * u / m.distance_mm, -p.y * u / m.distance_mm, u};
            const std::vector<OpticsRay> rays = rays_of_point(m, i, j, 64);
            ASSERT_EQ(rays.size(), 64u) << describe(params) << ": a bare thin lens blocks nothing";
            for (const OpticsRay& r : rays) {
                if (D_over_F > 1 + 1e-9) {
                    EXPECT_LT(miss(conjugate, r), 1e-9 * length(conjugate))
                        << describe(params) << ": ray " << str(origin_of(r)) << " + t " << str(dir_of(r))
                        << " misses the conjugate " << str(conjugate);
                } else {
                    // Conjugate 1e12 F away: the rays must be parallel to the chief ray within the
                    // angle the aperture subtends from there.
                    const Vec3 chief = normalized(conjugate);
                    EXPECT_LT(length(dir_of(r) - chief), 1e-9)
                        << describe(params) << ": direction " << str(dir_of(r)) << " vs " << str(chief);
                }
            }
        }
    }
}

TEST(OpticsExtremes, SensorAtTheFocalPlaneGivesParallelRaysAtEveryScale)
{
    const int W = 21, H = 15, i = 19, j = 2;
    for (double F : {1e-6, 1.0, 1e6}) {
        CameraParams params = thin_main(F, 1.4, F);  // D = F exactly
        params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = F * 1e-3;
        const PlenopticCamera m = with_film(make_camera(params), W, H);
        const Vec3 expected = normalized(-m.sensor.point(i + 0.5, j + 0.5));
        for (const OpticsRay& r : rays_of_point(m, i, j, 64))
            EXPECT_LT(length(dir_of(r) - expected), 1e-14) << describe(params) << " " << str(dir_of(r));
    }
}

// ------------------------------------------------------------------ thin main lens + thin array

// The system conjugate of sensor point p through microlens c (array parallel to the sensor at
// z = -D, sensor at -(D + d)), by the thin-lens equation twice, in homogeneous form so that d = f
// (image at infinity) is not a division by zero: microlens image X1 = (c + (c - p) u1/d, -D + u1)
// with u1 = f d / (d - f); as a homogeneous point (w = d - f): (c (d - f) + (c - p) f, (-D)(d - f) + f d).
// The main lens maps a homogeneous point (x, y, z, w) behind it to its thin-lens image
// (x, y, z, w + z/F): for w = 1, z = -s this is the point at v = s F / (s - F), scaled by -v/s.
struct Homog {
    double x, y, z, w;
};

Homog system_conjugate(Vec3 p, Vec3 c, double f, double d, double D, double F)
{
    const double w1 = d - f;
    Homog x1{c.x * w1 + (c.x - p.x) * f, c.y * w1 + (c.y - p.y) * f, -D * w1 + f * d, w1};
    return Homog{x1.x, x1.y, x1.z, x1.w + x1.z / F};
}

// Distance from homogeneous point X to a line; for X at infinity (w = 0), the angle between the
// line and the direction X.
double homog_miss(const Homog& X, const OpticsRay& r, double* scale)
{
    if (X.w == 0 || std::fabs(X.w) < 1e-300) {
        const Vec3 dir = normalized(Vec3{X.x, X.y, X.z});
        *scale = 1;
        return std::min(length(dir_of(r) - dir), length(dir_of(r) + dir));
    }
    const Vec3 point{X.x / X.w, X.y / X.w, X.z / X.w};
    *scale = length(point);
    return miss(point, r);
}

struct SystemCase {
    double F, N, D, pitch, f, d;
};

TEST(OpticsExtremes, PlenopticRaysOfASensorPointMeetAtTheSystemConjugate)
{
    std::vector<SystemCase> cases;
    for (double F : {1e-6, 1.0, 50.0, 1e6}) {
        const double D = 1.05 * F, pitch = 0.01 * F, f = 0.04 * F;
        for (double d : {f, f * (1 + 1e-12), f * (1 - 1e-12), 1.5 * f, 0.7 * f})
            cases.push_back(SystemCase{F, 1.0, D, pitch, f, d});
    }
    // Extreme microlenses in a camera of ordinary size; a huge main aperture so that rays pass.
    cases.push_back(SystemCase{16, 1e-5, 16.2, 0.08, 1e-6, 0.32});
    cases.push_back(SystemCase{16, 1.0, 16.2, 0.08, 1e6, 0.32});
    cases.push_back(SystemCase{16, 1.0, 16.2, 0.08, 0.32, 0.32});
    const int W = 31, H = 23;
    const int pixels[3][2] = {{15, 11}, {2, 3}, {29, 20}};
    for (const SystemCase& sc : cases) {
        for (GridType grid : {GridType::Hexagonal, GridType::Rectangular}) {
            CameraParams params = test::plenoptic_camera(grid, sc.pitch, sc.f, sc.d, sc.F, sc.N, sc.D);
            params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = sc.pitch / 7;
            ASSERT_EQ(check_camera(params), "") << describe(params);
            const PlenopticCamera m = with_film(make_camera(params), W, H);
            int met = 0;
            for (const auto& px : pixels) {
                const Vec3 p = m.sensor.point(px[0] + 0.5, px[1] + 0.5);
                const OwnLens lens_lookup = own_lens(m, p);
                ASSERT_TRUE(lens_lookup.found);
                const LensIndex lens = lens_lookup.lens;
                const Vec3 c = lens_centre_mm(m, lens);
                const Homog X = system_conjugate(p, c, sc.f, sc.d, sc.D, sc.F);
                for (const OpticsRay& r : rays_of_point(m, px[0], px[1], 128)) {
                    double scale;
                    const double err = homog_miss(X, r, &scale);
                    EXPECT_LT(err, 1e-9 * std::max(scale, sc.F))
                        << describe(params) << " pixel (" << px[0] << "," << px[1] << ") ray " << str(origin_of(r))
                        << " + t " << str(dir_of(r)) << " misses the conjugate (" << X.x << ", " << X.y << ", "
                        << X.z << ", w " << X.w << ")";
                    ++met;
                }
            }
            EXPECT_GT(met, 10) << describe(params) << ": too few rays pass to test the conjugate";
        }
    }
}

// ------------------------------------------------------------------ bare array (no main lens)

TEST(OpticsExtremes, BareArrayRaysMeetAtTheMicrolensConjugateEvenTiltedNearlyEdgeOn)
{
    const int W = 40, H = 30;
    for (double f : {1e-6, 0.3, 1e6}) {
        for (double d : {0.2, 0.3, 0.3 * (1 + 1e-12)}) {
            for (double tilt : {0.0, 1e-9, 45.0, 89.99}) {
                CameraParams params;
                test::add_array(&params, GridType::Hexagonal, 0.1, f, d);
                test::set_pose(&params, tilt, 0, 30, 0.01, -0.02, 0);
                params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
                ASSERT_EQ(check_camera(params), "") << describe(params);
                const PlenopticCamera m = with_film(make_camera(params), W, H);
                const double* deg = params.array.rotate_deg;
                for (int i : {5, 20, 37}) {
                    const int j = (i * 7) % H;
                    const Vec3 p = m.sensor.point(i + 0.5, j + 0.5);
                    const OwnLens lens_lookup = own_lens(m, p);
                    if (!lens_lookup.found)
                        continue;
                    const LensIndex lens = lens_lookup.lens;
                    // In the array's own frame (reference rotation): p at height -s below lens c.
                    const Vec2 c2 = lens_centre(GridType::Hexagonal, 0.1, lens);
                    const Vec3 c_local{c2.x, c2.y, 0};
                    const Vec3 p_local = test::reference_unrotate(deg, p - m.array.pose.centre_mm);
                    const double s = -p_local.z;
                    if (!(s > 0)) {  // the point is in front of the (steeply tilted) array: no light
                        EXPECT_TRUE(rays_of_point(m, i, j, 16).empty()) << describe(params);
                        continue;
                    }
                    // Homogeneous image of p by the microlens: (c (s - f) + (c - p) f, f s, w = s - f).
                    const double w = s - f;
                    const Vec3 xyz = w * c_local + f * (c_local - p_local);  // z: f s
                    const std::vector<OpticsRay> rays = rays_of_point(m, i, j, 64);
                    for (const OpticsRay& r : rays) {
                        const Vec3 o = origin_of(r);
                        // Origin on the array plane (the last element).
                        const Vec3 o_local = test::reference_unrotate(deg, o - m.array.pose.centre_mm);
                        EXPECT_LT(std::fabs(o_local.z), 1e-12 * (1 + length(o - m.array.pose.centre_mm)))
                            << describe(params) << ": origin " << str(o) << " is off the array plane";
                        if (std::fabs(w) <= 1e-9 * s) {
                            const Vec3 dir = normalized(test::reference_rotate(deg, xyz));
                            EXPECT_LT(length(dir_of(r) - dir), 1e-9) << describe(params) << " " << str(dir_of(r));
                        } else {
                            const Vec3 x = m.array.pose.centre_mm + test::reference_rotate(deg, (1 / w) * xyz);
                            EXPECT_LT(miss(x, r), 1e-9 * (length(x - o) + s))
                                << describe(params) << " pixel " << i << ": ray " << str(o) << " + t " << str(dir_of(r))
                                << " misses the microlens conjugate " << str(x);
                        }
                    }
                }
            }
        }
    }
}

// ------------------------------------------------------------------ pinhole main lens + thin array

TEST(OpticsExtremes, PinholeMainLensRaysAllLeaveThroughThePinhole)
{
    const int W = 24, H = 18;
    for (double f : {1e-6, 0.3, 1e6}) {
        for (double D : {1e-3, 20.0, 1e6}) {
            for (double tilt : {0.0, 45.0, 89.99}) {
                CameraParams params = pinhole_main(D);
                test::add_array(&params, GridType::Rectangular, 0.1, f, 0.35);
                test::set_pose(&params, 0, tilt, 10, 0, 0, 0);
                params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
                const std::string refusal = check_camera(params);
                if (!refusal.empty())
                    continue;  // the degenerate combination, refused as it must be
                const PlenopticCamera m = with_film(make_camera(params), W, H);
                int unblocked = 0, off_pinhole = 0, backwards = 0, not_unit = 0;
                OpticsRay example{};
                for (int j = 0; j < H; j += 5) {
                    for (int i = 0; i < W; i += 3) {
                        for (int n = 0; n < 8; ++n) {
                            OpticsRay r;
                            if (!(r = m.generate_ray(i, j, make_sample(i, j, n, 8))).passed)
                                continue;
                            ++unblocked;
                            if (!(r.origin_mm.x == 0 && r.origin_mm.y == 0 && r.origin_mm.z == 0))
                                ++off_pinhole;
                            if (!is_finite(dir_of(r)) || std::fabs(length(dir_of(r)) - 1) > 1e-12)
                                ++not_unit;
                            if (!(r.dir.z > 0)) {
                                if (backwards++ == 0)
                                    example = r;
                            }
                        }
                    }
                }
                EXPECT_EQ(off_pinhole, 0) << describe(params) << ": rays that do not start at the pinhole";
                EXPECT_EQ(not_unit, 0) << describe(params) << ": directions not finite and unit";
                EXPECT_EQ(backwards, 0) << describe(params) << ": " << backwards << " of " << unblocked
                                        << " unblocked rays point back into the camera (e.g. direction "
                                        << str(dir_of(example)) << "); light cannot reach the pinhole from behind "
                                        << "its own plane, so such samples must be blocked (BUG, docs/robustness.md)";
                RecordProperty(describe(params), unblocked);
            }
        }
    }
}

// ------------------------------------------------------------------ sweep over extreme values

// Every unblocked ray of every accepted parameter set: finite unit direction into the scene, origin
// on the last element's plane and inside its aperture; the chief ray finite; forward projections
// finite and inside the image.
void check_invariants(const CameraParams& params, int W, int H, int* models, long* rays)
{
    if (!check_camera(params).empty())
        return;
    const PlenopticCamera m = make_camera(params);
    ++*models;
    const std::string what = describe(params);
    const int pixel_list[5][2] = {{0, 0}, {W - 1, H - 1}, {W / 2, H / 2}, {W - 1, 0}, {W / 3, (2 * H) / 3}};
    for (const auto& px : pixel_list) {
        const int i = px[0], j = px[1];
        for (int n = 0; n < 6; ++n) {
            OpticsRay r;
            if (!(r = with_film(m, W, H).generate_ray(i, j, make_sample(i, j, n, 6))).passed)
                continue;
            ++*rays;
            const Vec3 o = origin_of(r), d = dir_of(r);
            ASSERT_TRUE(is_finite(o) && is_finite(d)) << what << " origin " << str(o) << " dir " << str(d);
            ASSERT_NEAR(length(d), 1.0, 1e-12) << what << " dir " << str(d);
            ASSERT_GT(d.z, 0.0) << what << " dir " << str(d);
            if (test::lens_kind(m) == "pinhole") {
                ASSERT_TRUE(o.x == 0 && o.y == 0 && o.z == 0) << what << " origin " << str(o);
            } else if (test::lens_kind(m) == "thin_lens") {
                ASSERT_EQ(o.z, 0.0) << what << " origin " << str(o) << " off the main-lens plane";
                ASSERT_LE(std::hypot(o.x, o.y), 0.5 * m.aperture_mm() * (1 + 1e-12))
                    << what << " origin " << str(o) << " outside the aperture " << m.aperture_mm();
            } else {
                const Vec3 local = mul_transposed(m.array.pose.rotation, o - m.array.pose.centre_mm);
                ASSERT_LE(std::fabs(local.z), 1e-12 * (1 + length(o - m.array.pose.centre_mm)))
                    << what << " origin " << str(o) << " off the array plane";
            }
        }
        const OpticsRay chief = with_film(m, W, H).chief_ray(i, j);
        ASSERT_TRUE(is_finite(origin_of(chief)) && is_finite(dir_of(chief))) << what << " chief ray";
        ASSERT_NEAR(length(dir_of(chief)), 1.0, 1e-12) << what << " chief ray";
    }
    // forward_project visits every lens that may image into the picture (bounded at 2^24): with
    // microimages far smaller than a pixel that is up to ~1e6 hits and a second per point, so the
    // sweep asks it only where the picture spans at most ~100 pitches across.
    if (m.array.grid != GridType::None && !(std::max(W, H) * m.sensor.pixel_size_mm[0] <= 100 * m.array.pitch_mm))
        return;
    for (double z : {1e-3, 1.0, 1e3, 1e9}) {
        const Vec3 point{0.05 * z, -0.03 * z, z};
        for (const PixelHit& hit : with_film(m, W, H).project(point)) {
            ASSERT_TRUE(std::isfinite(hit.u) && std::isfinite(hit.v)) << what << " z " << z;
            ASSERT_TRUE(hit.u >= -0.5 && hit.u < W - 0.5 && hit.v >= -0.5 && hit.v < H - 0.5)
                << what << " forward_project hit (" << hit.u << ", " << hit.v << ") outside the image";
        }
    }
}

TEST(OpticsExtremes, SweepOfExtremeValuesKeepsEveryInvariant)
{
    const double lengths[] = {1e-6, 1e-2, 1.0, 1e6};
    int models = 0;
    long rays = 0;
    for (int main_kind = 0; main_kind < 3; ++main_kind) {
        for (int array_kind = 0; array_kind < 3; ++array_kind) {
            for (double F : lengths) {
                for (double D_scale : {1.0, 1 + 1e-12, 3.0}) {
                    for (double pitch : lengths) {
                        for (double f : lengths) {
                            for (double d : {f, 0.5 * f, 1e-6, 1e6}) {
                                for (double pixel : {1e-6, 1e-2, 1.0}) {
                                    CameraParams p;
                                    if (main_kind == 1)
                                        p = thin_main(F, 2.0, F * D_scale);
                                    else if (main_kind == 2)
                                        p = pinhole_main(F * D_scale);
                                    if (array_kind > 0)
                                        test::add_array(&p, array_kind == 1 ? GridType::Hexagonal : GridType::Rectangular,
                                                        pitch, array_kind == 1 ? f : 0, d);
                                    if (array_kind == 0 && (pitch != lengths[0] || f != lengths[0] || d != f))
                                        continue;  // the array's values do not matter without an array
                                    if (array_kind == 1)
                                        test::set_pose(&p, 0, 0, 45, 0, 0, 0);
                                    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = pixel;
                                    check_invariants(p, 9, 7, &models, &rays);
                                    if (HasFatalFailure())
                                        return;
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    std::printf("checked %d accepted models, %ld unblocked rays\n", models, rays);
    EXPECT_GT(models, 1000);
    EXPECT_GT(rays, 10000);
}

} // namespace
} // namespace plenoptic
