// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the traced forward projection: through an ideal thin lens it must agree with the closed
// form (forward_project, polygons clipped exactly: code that shares none of its sampling); through
// a thin, weak singlet at a small stop it must land where the thin lens of the same focal length does.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/lens/prescription.h"
#include "plenoptic/projection/projection.h"
#include "plenoptic/core/test_util.h"
#include "plenoptic/projection/traced_projection.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;
using test::thin_lens_camera;

typedef std::map<std::pair<long long, long long>, PixelHit> HitsByLens;

HitsByLens by_lens(const std::vector<PixelHit>& hits)
{
    HitsByLens out;
    for (const PixelHit& h : hits)
        out[std::make_pair((long long)h.lens.k, (long long)h.lens.l)] = h;
    return out;
}

// Largest differences between two projections of one point, over lenses that carry more than
// `min_fraction` of the light in either (a lens carrying less may be found by one and not the other).
struct Difference {
    double position_px, fraction;
    int unmatched;
};

Difference compare(const std::vector<PixelHit>& a, const std::vector<PixelHit>& b, double min_fraction)
{
    Difference d{0, 0, 0};
    const HitsByLens ma = by_lens(a), mb = by_lens(b);
    for (int pass = 0; pass < 2; ++pass) {
        const HitsByLens& one = pass == 0 ? ma : mb;
        const HitsByLens& other = pass == 0 ? mb : ma;
        for (const auto& entry : one) {
            const auto found = other.find(entry.first);
            if (found == other.end()) {
                if (entry.second.fraction > min_fraction)
                    ++d.unmatched;
                continue;
            }
            if (entry.second.fraction > min_fraction || found->second.fraction > min_fraction) {
                d.position_px = std::max(d.position_px, std::hypot(entry.second.u - found->second.u,
                                                                   entry.second.v - found->second.v));
                d.fraction = std::max(d.fraction, std::fabs(entry.second.fraction - found->second.fraction));
            }
        }
    }
    return d;
}

struct Case {
    std::string name;
    CameraParams params;
    int W, H;
};

std::vector<Case> thin_lens_cases()
{
    std::vector<Case> cases;
    // Plenoptic 1.0 (d = f), hexagonal and rectangular; focused 2.0 (d < f); pinhole microlenses;
    // a posed array; no array. F = 50 mm, f/4, the array 52 mm behind the lens.
    cases.push_back(Case{"1.0 hexagonal", plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52), 301, 201});
    cases.push_back(Case{"1.0 rectangular", plenoptic_camera(GridType::Rectangular, 0.5, 2, 2, 50, 4, 52), 301, 201});
    cases.push_back(Case{"2.0 hexagonal", plenoptic_camera(GridType::Hexagonal, 0.5, 3, 1.5, 50, 4, 52), 301, 201});
    cases.push_back(Case{"pinholes", plenoptic_camera(GridType::Rectangular, 0.5, 0, 2, 50, 4, 52), 301, 201});
    CameraParams posed = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52);
    test::set_pose(&posed, 0, 0, 7, 0.1, -0.05, 0);
    cases.push_back(Case{"posed", posed, 301, 201});
    cases.push_back(Case{"no array", thin_lens_camera(50, 4, 52), 301, 201});
    for (Case& c : cases) {
        c.params.sensor.pixel_size_mm[0] = c.params.sensor.pixel_size_mm[1] = 0.01;
    }
    return cases;
}

TEST(TracedProjection, ThroughAThinLensAgreesWithTheClosedForm)
{
    const TracedProjectionOptions options = default_traced_projection_options();
    // Points: in focus on the array (z = F D / (D - F) = 1300 mm), nearer and farther, off axis.
    const double points[][3] = {{0, 0, 1300}, {3, -2, 1300}, {0.7, 0.4, 900}, {-5, 3, 2500},
                                {10, 6, 700}, {-2, -9, 5000}, {0.13, 0.29, 1150},
                                {0.3, -0.2, 400}, {-0.5, 0.3, 600}, {0.05, 0.02, 250}};
    for (const Case& c : thin_lens_cases()) {
        const PlenopticCamera m = make_camera(c.params);
        ASSERT_EQ(test::lens_kind(m), "thin_lens");
        const bool pinholes = c.params.array.given && c.params.array.lens == MicrolensType::Pinhole;
        size_t images = 0;
        double worst_px = 0, worst_fraction = 0;
        for (const auto& p : points) {
            if (pinholes && p[0] == 0 && p[1] == 0 && p[2] == 1300)
                continue;  // focused on a pinhole: every ray passes it (no single ray to find)
            const std::vector<PixelHit> closed = with_film(m, c.W, c.H).project(Vec3{p[0], p[1], p[2]});
            const std::vector<PixelHit> traced = forward_project_traced(with_film(m, c.W, c.H), Vec3{p[0], p[1], p[2]}, options);
            images += closed.size();
            // Pinholes: single rays, found by Newton's method to a tiny fraction of a pixel. No
            // array: the spot's centroid (weighted by solid angle) against the chief ray, within a
            // few thousandths. Thin microlenses: centroids of sampled light, a few hundredths.
            const bool bare = m.array.grid == GridType::None;
            const Difference d = compare(closed, traced, pinholes || bare ? 0.0 : 0.02);
            const std::string where = c.name + " point (" + std::to_string(p[0]) + ", " + std::to_string(p[1]) +
                                      ", " + std::to_string(p[2]) + ")";
            EXPECT_EQ(d.unmatched, 0) << where << ": " << closed.size() << " closed-form images, " << traced.size()
                                      << " traced";
            EXPECT_LE(d.position_px, pinholes ? 1e-6 : bare ? 0.005 : 0.03) << where;
            EXPECT_LE(d.fraction, pinholes || bare ? 1e-12 : 0.01) << where;
            worst_px = std::max(worst_px, d.position_px);
            worst_fraction = std::max(worst_fraction, d.fraction);
        }
        std::printf("  %-16s %3zu images, largest difference %.2g px, fraction %.2g\n", c.name.c_str(), images, worst_px,
                    worst_fraction);
        EXPECT_GE(images, 3u) << c.name << ": the test points image too rarely to test anything";
    }
}

// A thin, weak biconvex singlet (n = 1.5, R = +-2000 mm, 0.5 mm thick: F = 2000.1 mm) with a small
// stop right behind it; the thin lens of the same focal length at the same place.
Prescription weak_singlet()
{
    Prescription lens;
    lens.surfaces.push_back(LensSurface{2000, 0.5, 1.5, 40, false, 1});
    lens.surfaces.push_back(LensSurface{-2000, 0.01, 1, 40, false, 2});
    lens.surfaces.push_back(LensSurface{0, 0, 1, 20, true, 3});
    return lens;
}

TEST(TracedProjection, AWeakSingletImagesWhereTheThinLensDoes)
{
    const Prescription lens = weak_singlet();
    const ParaxialData p = paraxial_data(lens);
    ASSERT_TRUE(p.valid);
    // Optics-frame z (rear vertex at 0, +z towards the scene) of the principal planes: the thin
    // lens stands for the singlet with the gap between them removed.
    const double L = p.rear_vertex_z;
    const double front_h = L - p.front_principal_z, rear_h = L - p.rear_principal_z;
    const double D = 2100;  // behind the rear vertex (the stop)
    CameraParams real = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 2000, 100, D);
    test::use_prescription(&real, lens);
    CameraParams thin = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, p.efl_mm, p.efl_mm / p.exit_pupil_mm, D + rear_h);
    for (CameraParams* c : {&real, &thin}) {
        c->sensor.pixel_size_mm[0] = c->sensor.pixel_size_mm[1] = 0.01;
    }
    const PlenopticCamera mr = with_film(make_camera(real), 301, 201), mt = with_film(make_camera(thin), 301, 201);
    ASSERT_EQ(test::lens_kind(mr), "prescription");
    const double points[][3] = {{0, 0, 30000}, {5, -3, 25000}, {-20, 12, 50000}, {1, 0.5, 4000}};
    for (const auto& q : points) {
        const std::vector<PixelHit> a = mt.project(Vec3{q[0], q[1], q[2]});
        const Vec3 in_real{q[0], q[1], q[2] + front_h};
        const std::vector<PixelHit> b = mr.project(in_real);
        ASSERT_FALSE(a.empty());
        const Difference d = compare(a, b, 0.05);
        EXPECT_EQ(d.unmatched, 0) << "point z " << q[2];
        EXPECT_LE(d.position_px, 0.05) << "point z " << q[2];
        EXPECT_LE(d.fraction, 0.02) << "point z " << q[2];
    }
}

TEST(TracedProjection, RefusesPointsBehindTheFrontWindow)
{
    const PlenopticCamera m = with_film(make_camera(plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52)), 301, 201);
    const TracedProjectionOptions options = default_traced_projection_options();
    EXPECT_TRUE(forward_project_traced(m, Vec3{0, 0, -10}, options).empty());
    EXPECT_TRUE(forward_project_traced(m, Vec3{0, 0, 0}, options).empty());
    EXPECT_TRUE(forward_project_traced(m, Vec3{NAN, 0, 100}, options).empty());
}

} // namespace
} // namespace plenoptic
