// SPDX-License-Identifier: AGPL-3.0-or-later
// Conic and even-aspheric surfaces (prescription.h): the sag against closed forms, the exact
// intersection against roots found here by bisection on the test's own sag formulas, a hyperboloid
// (k = -n^2) that focuses an axial parallel beam without spherical aberration while the sphere of
// the same radius shows the third-order amount, and the refusals with their line and value.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "plenoptic/core/json.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/prescription.h"

namespace plenoptic {
namespace {

LensSurface conic_surface(double radius, double k, double aperture = 20)
{
    LensSurface s{radius, 10, 1.5, aperture, false, 1};
    s.conic = k;
    return s;
}

// The conic's sag written the other way: (R - sign(R) sqrt(R^2 - (1 + k) r^2)) / (1 + k), and
// r^2 / (2 R) for the paraboloid.
double closed_conic_sag(double R, double k, double r)
{
    if (k == -1)
        return r * r / (2 * R);
    return (R - (R > 0 ? 1 : -1) * std::sqrt(R * R - (1 + k) * r * r)) / (1 + k);
}

TEST(Asphere, SagAgainstClosedForms)
{
    for (double R : {30.0, -45.0})
        for (double k : {0.0, -1.0, -2.25, 0.6, -0.4})
            for (double r : {0.0, 1.0, 5.5, 9.9}) {
                const double expected = closed_conic_sag(R, k, r);
                EXPECT_NEAR(surface_sag_mm(conic_surface(R, k), r), expected, 1e-12 * (1 + std::fabs(expected)))
                    << R << " " << k << " " << r;
            }
    // Pure terms on a flat surface: a4 r^4 + a6 r^6.
    LensSurface plate{0, 5, 1.5, 20, false, 1};
    plate.aspheric_count = 2;
    plate.aspheric[0] = 2e-4;
    plate.aspheric[1] = -3e-7;
    EXPECT_NEAR(surface_sag_mm(plate, 7), 2e-4 * std::pow(7, 4) - 3e-7 * std::pow(7, 6), 1e-12);
    // Beyond the conic's reach (k = 1: r <= |R| / sqrt 2) the sag is undefined.
    EXPECT_TRUE(std::isnan(surface_sag_mm(conic_surface(30, 1), 22)));
    EXPECT_FALSE(std::isnan(surface_sag_mm(conic_surface(30, 1), 21)));
}

// The root of z(t) - vertex - sag(r(t)) on [lo, hi] by bisection with the test's sag.
template <class Sag>
double bisect(const LensRay& ray, double vertex, Sag sag, double lo, double hi)
{
    const auto f = [&](double t) {
        const Vec3 p = ray.origin + t * ray.dir;
        return p.z - vertex - sag(std::hypot(p.x, p.y));
    };
    const bool rising = f(hi) > f(lo);
    for (int k = 0; k < 200; ++k) {
        const double mid = 0.5 * (lo + hi);
        ((f(mid) < 0) == rising ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

void expect_hit(const LensSurface& s, double vertex, const LensRay& ray, double t_expected, double dsag_dr_at_hit)
{
    Vec3 hit, normal;
    ASSERT_TRUE(meet_aspheric_surface(s, vertex, ray, &hit, &normal));
    const Vec3 expected = ray.origin + t_expected * ray.dir;
    EXPECT_NEAR(hit.x, expected.x, 1e-8);
    EXPECT_NEAR(hit.y, expected.y, 1e-8);
    EXPECT_NEAR(hit.z, expected.z, 1e-8);
    // The normal is parallel to (-dz/dr x/r, -dz/dr y/r, 1).
    const double r = std::hypot(hit.x, hit.y);
    const Vec3 n = normalized(Vec3{-dsag_dr_at_hit * hit.x / r, -dsag_dr_at_hit * hit.y / r, 1});
    EXPECT_NEAR(std::fabs(dot(n, normal)), 1, 1e-9);
}

TEST(Asphere, IntersectionAgainstBisection)
{
    const LensRay ray{Vec3{1, 2, -10}, normalized(Vec3{0.05, -0.03, 1})};
    // Conics: an ellipsoid, a paraboloid, a hyperboloid, on either side of the vertex.
    for (double R : {30.0, -40.0})
        for (double k : {0.5, -1.0, -3.0}) {
            const LensSurface s = conic_surface(R, k);
            const auto sag = [&](double r) { return closed_conic_sag(R, k, r); };
            const double t = bisect(ray, 5, sag, 0, 25);
            const double r = std::hypot((ray.origin + t * ray.dir).x, (ray.origin + t * ray.dir).y);
            const double h = 1e-6;
            expect_hit(s, 5, ray, t, (sag(r + h) - sag(r - h)) / (2 * h));
        }
    // A pure r^4 term on a flat surface, and on a sphere.
    for (double R : {0.0, 60.0}) {
        LensSurface s{R, 5, 1.5, 30, false, 1};
        s.aspheric_count = 1;
        s.aspheric[0] = -4e-4;
        const auto sag = [&](double r) { return (R == 0 ? 0 : closed_conic_sag(R, 0, r)) - 4e-4 * std::pow(r, 4); };
        const double t = bisect(ray, 5, sag, 0, 25);
        const double r = std::hypot((ray.origin + t * ray.dir).x, (ray.origin + t * ray.dir).y);
        expect_hit(s, 5, ray, t, (sag(r + 1e-6) - sag(r - 1e-6)) / 2e-6);
    }
}

// A plano-convex lens, flat side to the object, its rear surface of radius -R and conic k: a stop,
// the flat (index n), the conic (into air).
Prescription plano_convex(double R, double k, double n)
{
    Prescription lens;
    lens.surfaces.push_back(LensSurface{0, 1, 0, 30, true, 1});
    lens.surfaces.push_back(LensSurface{0, 8, n, 30, false, 2});
    LensSurface rear{-R, 100, 1, 30, false, 3};
    rear.conic = k;
    lens.surfaces.push_back(rear);
    return lens;
}

// Where the ray leaving the lens at height h (parallel to the axis before it) crosses the axis.
double axis_crossing(const TracingLens& lens, double h)
{
    const Traced out = lens.trace_from_object(LensRay{Vec3{h, 0, -5}, Vec3{0, 0, 1}});
    EXPECT_EQ(out.result, TraceResult::Passed) << h;
    return out.ray.origin.z - out.ray.origin.x * out.ray.dir.z / out.ray.dir.x;
}

TEST(Asphere, HyperboloidFocusesAParallelBeamWithoutSphericalAberration)
{
    const double n = 1.5, R = 50;
    const Prescription conic = plano_convex(R, -n * n, n);
    ASSERT_FALSE(check_prescription(conic).any()) << check_prescription(conic).message;
    const TracingLens traced(conic);
    const double rear_vertex = 9, paraxial_focus = rear_vertex + R / (n - 1);  // back focus R / (n - 1)
    for (double h : {0.5, 2.0, 5.0, 9.0, 14.0})
        EXPECT_NEAR(axis_crossing(traced, h), paraxial_focus, 1e-6) << h;

    // The sphere: the third-order longitudinal aberration of this surface (glass into air, beam
    // parallel in the glass), from the sag's r^4 difference to the aberration-free hyperboloid
    // n^2 r^4 / (8 R^3), an optical path error (n - 1) n^2 r^4 / (8 R^3), is
    // n^2 h^2 / (2 (n - 1) R), the marginal focus nearer the lens.
    const TracingLens sphere(plano_convex(R, 0, n));
    for (double h : {1.0, 2.0, 3.0}) {
        const double shift = axis_crossing(sphere, h) - paraxial_focus;
        const double third_order = -n * n * h * h / (2 * (n - 1) * R);
        EXPECT_LT(shift, 0) << h;
        EXPECT_NEAR(shift / third_order, 1, 0.05) << h << ": " << shift << " against " << third_order;
    }
}

TEST(Asphere, RaysBeyondTheSagAreBlockedNotNaN)
{
    // k = 1 and R = 30: the sag ends 21.2 mm from the axis; a ray aimed past it is blocked.
    Prescription lens = plano_convex(50, -2.25, 1.5);
    const TracingLens traced(lens);
    const Traced out = traced.trace_from_object(LensRay{Vec3{40, 0, -5}, Vec3{0, 0, 1}});
    EXPECT_NE(out.result, TraceResult::Passed);
    LensSurface s = conic_surface(30, 1);
    Vec3 hit, normal;
    EXPECT_FALSE(meet_aspheric_surface(s, 0, LensRay{Vec3{25, 0, -5}, Vec3{0, 0, 1}}, &hit, &normal));
}

TEST(Asphere, RefusalsNameLineAndValue)
{
    const struct {
        const char* text;
        int line;
        const char* says;
    } refused[] = {
        {"0 2 0 10 0 -1\n60 5 1.5 20\n-60 40 1 20\n", 1, "the stop is a flat opening; it takes no conic"},
        {"0 2 0 10 0 0 1e-5\n60 5 1.5 20\n-60 40 1 20\n", 1, "the stop is a flat opening"},
        {"0 2 0 10\n20 5 1.5 30 0 1\n-60 40 1 30\n", 2, "with the conic constant 1 and radius 20 mm the sag is undefined beyond 14.1421 mm"},
        {"0 2 0 10\n1e13 5 1.5 20 0 -2\n-60 40 1 20\n", 2, "the conic constant -2 is given on a flat surface"},
        {"0 2 0 10\n60 5 1.5 20 0 0 1e300 1e300\n-60 40 1 20\n", 2, "the aspheric terms make the sag exceed"},
        {"0 2 0 10\n60 1 1.5 20 0 0 0.01\n-60 40 1 20\n", 2, "cross inside their clear apertures"},
        {"0 2 0 10\n60 5 1.5 20 0 nan\n-60 40 1 20\n", 2, "'nan' is not a finite number"},
    };
    for (const auto& r : refused) {
        const ParsedPrescription bad = parse_lens_file(r.text);
        EXPECT_EQ(bad.error.line, r.line) << r.text;
        EXPECT_NE(bad.error.message.find(r.says), std::string::npos) << bad.error.message;
    }
    // Read back: the conic and the terms in order, the count as written.
    const ParsedPrescription good = parse_lens_file("0 2 0 10\n60 5 1.5 20 0 -0.5 1e-6 -2e-9\n-60 40 1 20\n");
    ASSERT_FALSE(good.error.any()) << good.error.message;
    const LensSurface& s = good.prescription.surfaces[1];
    EXPECT_EQ(s.conic, -0.5);
    EXPECT_EQ(s.aspheric_count, 2);
    EXPECT_EQ(s.aspheric[0], 1e-6);
    EXPECT_EQ(s.aspheric[1], -2e-9);
    EXPECT_FALSE(good.prescription.surfaces[2].is_aspheric());
    // An unphysical term inline: conic not finite.
    Prescription p = good.prescription;
    p.surfaces[1].conic = INFINITY;
    EXPECT_NE(check_prescription(p).message.find("conic constant must be finite"), std::string::npos);
    EXPECT_EQ(check_prescription(p).line, 2);
}

// The metadata names a conic or aspheric surface's terms (only there), and its paraxial data are
// those of the base spheres.
TEST(Asphere, MetadataAndFirstOrderData)
{
    const ParsedPrescription plain = parse_lens_file("0 2 0 10\n60 5 1.5 20\n-60 40 1 20\n");
    const ParsedPrescription asph = parse_lens_file("0 2 0 10\n60 5 1.5 20 0 -0.5 1e-6 0\n-60 40 1 20 0 0 -2e-6\n");
    ASSERT_FALSE(plain.error.any() || asph.error.any()) << asph.error.message;
    const LensPlacement at{55, false, 0, ""};
    const MetadataJson without = main_lens_metadata(make_prescription_lens(plain.prescription, 0, true, 55).get(), at);
    const MetadataJson with = main_lens_metadata(make_prescription_lens(asph.prescription, 0, true, 55).get(), at);
    for (const MetadataJson& s : without["prescription"]["surfaces"])
        EXPECT_FALSE(s.contains("conic") || s.contains("aspheric"));
    EXPECT_EQ(with["prescription"]["surfaces"][1]["conic"].get<double>(), -0.5);
    EXPECT_EQ(with["prescription"]["surfaces"][1]["aspheric"].size(), 2u);
    EXPECT_EQ(with["prescription"]["surfaces"][1]["aspheric"][0].get<double>(), 1e-6);
    EXPECT_FALSE(with["prescription"]["surfaces"][2].contains("conic"));
    EXPECT_EQ(with["prescription"]["surfaces"][2]["aspheric"][0].get<double>(), -2e-6);
    MetadataJson trimmed = with;
    trimmed["prescription"]["surfaces"][1].erase("conic");
    trimmed["prescription"]["surfaces"][1].erase("aspheric");
    trimmed["prescription"]["surfaces"][2].erase("aspheric");
    EXPECT_EQ(trimmed["paraxial"], without["paraxial"]);
    EXPECT_EQ(trimmed["prescription"], without["prescription"]);
}

} // namespace
} // namespace plenoptic
