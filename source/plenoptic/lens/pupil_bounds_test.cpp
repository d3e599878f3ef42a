// SPDX-License-Identifier: AGPL-3.0-or-later
// The pupil bounds (lens/pupil_bounds.h) hold every passing ray: a brute-force search over
// the exit pupil's plane finds no ray that passes the exact lens outside disc_for, and may_pass
// never refuses one. Ray generation samples these discs (no array) and rejects rays outside them
// without a trace (with an array), so a ray they missed would be light lost.

#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/lens/pupil_bounds.h"
#include "plenoptic/core/setup_progress.h"
#include "plenoptic/core/test_util.h"

#ifndef PLENOPTIC_LENSES_DIR
#error "PLENOPTIC_LENSES_DIR must name the lenses/ folder (see CMakeLists.txt)"
#endif

namespace plenoptic {
namespace {

using test::vignetting_triplet;

// A lens of the catalogue (lenses/) stopped to `f_number`.
Prescription catalogue_lens(const std::string& file, double f_number)
{
    std::ifstream in(std::string(PLENOPTIC_LENSES_DIR) + "/" + file);
    std::stringstream text;
    text << in.rdbuf();
    ParsedPrescription parsed = parse_lens_file(text.str());
    EXPECT_FALSE(parsed.error.any()) << parsed.error.message;
    Prescription lens = parsed.prescription;
    for (LensSurface& s : lens.surfaces)
        if (s.stop)
            s.aperture_mm = stop_diameter_for_f_number(lens, f_number);
    return lens;
}

Prescription laikin_wide_angle(double f_number)
{
    return catalogue_lens("wide_angle_22mm_laikin_f3.5.dat", f_number);
}

struct Case {
    const char* name;
    Prescription lens;
    double plane_z;  // the sensor (no array) or the array plane
};

// Every point of a fine grid over the rear element's whole shadow on the exit pupil's plane, from
// field points on a ray out of the axis (between the bounds' bins as well as on them, and beyond
// the field's edge): a passing ray lies in the disc, and may_pass agrees. With `dz`, the field
// points lie that far off the bounds' plane (a microlens displaced along the axis or tilted): then
// only may_pass is asserted (the discs are the plane's), and that it still refuses at least
// `refuses_dark` of the rays that do not pass.
int expect_bounds_hold(const Case& c, double dz = 0, double refuses_dark = 0)
{
    const std::shared_ptr<const MainLens> traced = make_prescription_lens(c.lens, 0, true);
    const PupilBounds bounds(c.lens, *traced, c.plane_z);
    const double pupil_z = traced->exit_pupil_centre().z;
    const double rear = 0.5 * c.lens.surfaces.back().aperture_mm;
    const double edge = bounds.field_radius_mm();
    EXPECT_GT(edge, 0) << c.name;
    if (!(edge > 0))
        return 0;
    const double azimuth = 0.7;  // radians: the discs turn with the point
    int passing = 0, outside = 0, refused = 0, beyond = 0, dark = 0, dark_refused = 0;
    for (int k = 0; k <= 90; ++k) {
        const double r = 1.15 * edge * k / 90;
        const Vec3 p{r * std::cos(azimuth), r * std::sin(azimuth), c.plane_z + dz};
        const PupilDisc disc = bounds.disc_for(p);
        // The rear opening's shadow on the pupil's plane (both its vertex plane and its rim's
        // sag lie within 2 rear radii of z = 0), widened.
        const double scale = (pupil_z - p.z) / (0 - p.z);
        const double half = 3 * rear * std::fabs(scale) + 1;
        const Vec3 centre{p.x * (1 - scale), p.y * (1 - scale), pupil_z};
        const int n = 160;
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const Vec3 x{centre.x - half + (i + 0.5) * 2 * half / n, centre.y - half + (j + 0.5) * 2 * half / n, pupil_z};
                if (!traced->to_scene(p, x - p, true).passed) {
                    ++dark;
                    dark_refused += !bounds.may_pass(p, x - p);
                    continue;
                }
                ++passing;
                if (dz == 0 && std::hypot(x.x - disc.centre.x, x.y - disc.centre.y) > disc.radius)
                    ++outside;
                if (!bounds.may_pass(p, x - p))
                    ++refused;
                if (dz == 0 && r > edge)
                    ++beyond;
            }
        }
    }
    EXPECT_GT(passing, 10000) << c.name;
    EXPECT_EQ(outside, 0) << c.name;
    EXPECT_EQ(refused, 0) << c.name;
    EXPECT_EQ(beyond, 0) << c.name;
    EXPECT_GE(dark_refused, refuses_dark * dark) << c.name << ", " << dark_refused << " of " << dark;
    std::printf("%s, %g mm off the plane: %d passing rays, %d of %d others refused\n", c.name, dz, passing,
                dark_refused, dark);
    return passing;
}

TEST(PupilBounds, HoldEveryPassingRayOfTheTriplet)
{
    expect_bounds_hold(Case{"triplet, sensor 45 mm behind", vignetting_triplet(), -45});
    expect_bounds_hold(Case{"triplet, array 37 mm behind", vignetting_triplet(), -37});
}

// The triplet with a paraboloid front surface and an r^4, r^6 profile on its rear surface: the
// asphere changes which rays pass (the brute-force count differs from the spherical triplet's by
// more than 3 %), and the bounds still hold every one.
TEST(PupilBounds, HoldEveryPassingRayOfAnAsphericTriplet)
{
    Prescription aspheric = vignetting_triplet();
    aspheric.surfaces[0].conic = -1;
    LensSurface& rear = aspheric.surfaces.back();
    rear.aspheric_count = 2;
    rear.aspheric[0] = -1e-4;
    rear.aspheric[1] = -5e-7;
    ASSERT_FALSE(check_prescription(aspheric).any()) << check_prescription(aspheric).message;
    const int spheres = expect_bounds_hold(Case{"triplet, sensor 45 mm behind", vignetting_triplet(), -45});
    const int aspheres = expect_bounds_hold(Case{"aspheric triplet, sensor 45 mm behind", aspheric, -45});
    EXPECT_GT(std::fabs(double(aspheres - spheres)) / spheres, 0.03) << spheres << " against " << aspheres;
    expect_bounds_hold(Case{"aspheric triplet, array 37 mm behind", aspheric, -37});
}

TEST(PupilBounds, HoldEveryPassingRayOfTheWideAngle)
{
    expect_bounds_hold(Case{"Laikin f/3.5", laikin_wide_angle(3.5), -40});
    expect_bounds_hold(Case{"Laikin f/2", laikin_wide_angle(2), -40});
}

// Rays from points off the bounds' plane (lenses displaced along the axis or tilted, a tilted
// array: the renderer asks may_pass from where a ray leaves the array): tested from where their
// lines cross the plane, no passing ray is refused, and most of those that do not pass still are.
// Tested from the points themselves, as if they lay in the plane, 2 mm off it would refuse passing
// rays.
TEST(PupilBounds, MayPassHoldsForPointsOffThePlane)
{
    for (double dz : {-2.0, -0.05, 0.05, 2.0}) {
        expect_bounds_hold(Case{"triplet, array 37 mm behind", vignetting_triplet(), -37}, dz, 0.5);
        expect_bounds_hold(Case{"Laikin f/3.5", laikin_wide_angle(3.5), -40}, dz, 0.5);
    }
}

TEST(PupilBounds, MayPassRefusesWhatMissesTheDisc)
{
    const Prescription lens = vignetting_triplet();
    const std::shared_ptr<const MainLens> traced = make_prescription_lens(lens, 0, true);
    const PupilBounds bounds(lens, *traced, -45);
    const Vec3 p{2, 1, -45};
    const PupilDisc disc = bounds.disc_for(p);
    const Vec3 inside{disc.centre.x + 0.5 * disc.radius, disc.centre.y, disc.centre.z};
    const Vec3 outside{disc.centre.x, disc.centre.y + 1.01 * disc.radius, disc.centre.z};
    EXPECT_TRUE(bounds.may_pass(p, inside - p));
    EXPECT_FALSE(bounds.may_pass(p, outside - p));
    EXPECT_TRUE(bounds.may_pass(p, p - inside));  // heading away from the pupil: the trace decides
    EXPECT_FALSE(bounds.may_pass(Vec3{2 * bounds.field_radius_mm(), 0, -45}, Vec3{0, 0, 1}));  // beyond the field
}

// disc_holding holds disc_for of every point of the region: points on a fine polar grid over the
// region (its rim included), for regions on the axis, straddling it, between bins, across bins and
// beyond the field's edge, each at several azimuths. And it is tight enough to be worth having: for a
// microlens cell far from the axis it is barely larger than the disc of the cell's centre.
TEST(PupilBounds, DiscHoldingHoldsTheDiscsOfEveryPointOfTheRegion)
{
    const Prescription lens = laikin_wide_angle(3.5);
    const std::shared_ptr<const MainLens> traced = make_prescription_lens(lens, 0, true);
    const PupilBounds bounds(lens, *traced, -40);
    const double edge = bounds.field_radius_mm();
    ASSERT_GT(edge, 0);
    int checked = 0, escaped = 0;
    for (double radius : {0.0, 0.00001, 0.012, 0.1, 0.7 * edge / 48, 3 * edge / 48}) {
        for (int k = 0; k <= 60; ++k) {
            const double r = 1.1 * edge * k / 60;
            for (double azimuth : {0.0, 0.4, 2.5, -1.9}) {
                const Vec3 centre{r * std::cos(azimuth), r * std::sin(azimuth), -40};
                const PupilDisc held = bounds.disc_holding(centre, radius);
                for (int ring = 0; ring <= 8; ++ring) {
                    for (int a = 0; a < 48; ++a) {
                        const double t = 2 * kPi * a / 48, s = radius * ring / 8;
                        const Vec3 q{centre.x + s * std::cos(t), centre.y + s * std::sin(t), -40};
                        const PupilDisc disc = bounds.disc_for(q);
                        if (!(disc.radius > 0))
                            continue;
                        ++checked;
                        const double reach = std::hypot(disc.centre.x - held.centre.x, disc.centre.y - held.centre.y) + disc.radius;
                        if (!(reach <= held.radius * (1 + 1e-12) + 1e-12))
                            ++escaped;
                    }
                }
            }
        }
    }
    EXPECT_GT(checked, 50000);
    EXPECT_EQ(escaped, 0);
    // A 20 um cell half-way out: the held disc exceeds the centre's by little.
    const Vec3 half_way{0.5 * edge, 0.2, -40};
    const PupilDisc own = bounds.disc_for(half_way), held = bounds.disc_holding(half_way, 0.012);
    EXPECT_LT(held.radius, 1.1 * own.radius);
    EXPECT_EQ(bounds.disc_holding(Vec3{2 * edge, 0, -40}, 0.01).radius, 0);  // beyond the field
}


// The tight discs (made for aimed samples) and their cutting discs hold every passing ray, by
// brute force: from points of microlens-sized cells at field radii drawn at random (between the
// spans' measured radii, and beyond the field's edge), rays to a grid over the whole rear shadow
// and to a ring just outside each disc; none that the renderer traces (may_pass: beyond the
// field's edge the bounds found, it traces none) passes outside disc_holding(.., true) or any
// cutting disc of discs_holding (the two on the line through the axis, and the off-axis pair
// where it is kept). PUPIL_BOUNDS_CELLS sets the number of cells (100; 2000 passed too). And they are tighter than the bounds' own on the axis (within 0.02 % of the
// region's radius measured here by bisection, against 2 to 7 %).
double expect_tight_discs_hold(const char* name, const Prescription& lens, double plane_z, int* pair_cells = nullptr)
{
    const std::shared_ptr<const MainLens> traced = make_prescription_lens(lens, 0, true);
    const PupilBounds bounds(lens, *traced, plane_z, true);
    EXPECT_TRUE(bounds.has_tight()) << name;
    const double pupil_z = traced->exit_pupil_centre().z;
    const double rear = 0.5 * lens.surfaces.back().aperture_mm;
    const double edge = bounds.field_radius_mm();
    EXPECT_GT(edge, 0) << name;
    std::uint64_t state = 12345;
    auto uniform = [&state]() {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return double(state >> 11) / 9007199254740992.0;
    };
    int passing = 0, outside = 0, ring_passing = 0, cut_outside = 0, cuts = 0, pairs = 0;
    const double cell = 0.0115;  // a 20 um hexagonal cell's circumradius
    const int cells = std::getenv("PUPIL_BOUNDS_CELLS") ? std::atoi(std::getenv("PUPIL_BOUNDS_CELLS")) : 100;
    for (int k = 0; k < cells; ++k) {
        const double r = 1.05 * edge * uniform(), azimuth = 2 * kPi * uniform();
        const Vec3 c{r * std::cos(azimuth), r * std::sin(azimuth), plane_z};
        const PupilDisc held = bounds.disc_holding(c, cell, true);
        PupilDisc all[PupilBounds::kMaxDiscs];
        const int count = bounds.discs_holding(c, cell, all);
        EXPECT_EQ(all[0].radius, held.radius) << name;
        cuts += count >= 3 ? 1 : 0;
        pairs += count == 5 ? 1 : 0;
        for (int q = 0; q < 3; ++q) {
            const double s = cell * std::sqrt(uniform()), t = 2 * kPi * uniform();
            const Vec3 p{c.x + s * std::cos(t), c.y + s * std::sin(t), plane_z};
            const double scale = (pupil_z - plane_z) / (0 - plane_z);
            const double half = 3 * rear * std::fabs(scale) + 1;
            const Vec3 centre{p.x * (1 - scale), p.y * (1 - scale), pupil_z};
            const int n = 96;
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const Vec3 x{centre.x - half + (i + uniform()) * 2 * half / n,
                                 centre.y - half + (j + uniform()) * 2 * half / n, pupil_z};
                    // What the renderer traces: a ray the bounds refuse (beyond the field's edge
                    // they found) never is.
                    if (!bounds.may_pass(p, x - p) || !traced->to_scene(p, x - p, true).passed)
                        continue;
                    ++passing;
                    if (std::hypot(x.x - held.centre.x, x.y - held.centre.y) > held.radius)
                        ++outside;
                    for (int d = 1; d < count; ++d)
                        if (std::hypot(x.x - all[d].centre.x, x.y - all[d].centre.y) > all[d].radius)
                            ++cut_outside;
                }
            if (!(held.radius > 0))
                continue;
            for (int d = 0; d < count; ++d)
                for (int a = 0; a < 720; ++a) {
                    const double u = 2 * kPi * (a + uniform()) / 720, rho = all[d].radius * (1 + 1e-9);
                    const Vec3 x{all[d].centre.x + rho * std::cos(u), all[d].centre.y + rho * std::sin(u), pupil_z};
                    if (bounds.may_pass(p, x - p) && traced->to_scene(p, x - p, true).passed)
                        ++ring_passing;
                }
        }
    }
    EXPECT_GT(passing, 20000) << name;
    EXPECT_EQ(outside, 0) << name;
    EXPECT_EQ(ring_passing, 0) << name;
    EXPECT_EQ(cut_outside, 0) << name;
    EXPECT_GT(cuts, 50) << name;  // off the axis the cells have cutting discs
    if (pair_cells)
        *pair_cells = pairs;

    // Tight on the axis: the region's radius by bisection along 16 directions from the axis.
    const Vec3 axis{0, 0, plane_z};
    double measured = 0;
    for (int a = 0; a < 16; ++a) {
        const double u = 2 * kPi * a / 16;
        double in = 0, out = 3 * rear * std::fabs((pupil_z - plane_z) / plane_z) + 1;
        for (int s = 0; s < 50; ++s) {
            const double mid = 0.5 * (in + out);
            const Vec3 x{mid * std::cos(u), mid * std::sin(u), pupil_z};
            (traced->to_scene(axis, x - axis, true).passed ? in : out) = mid;
        }
        measured = std::max(measured, in);
    }
    const PupilDisc tight = bounds.disc_holding(axis, 0, true), loose = bounds.disc_holding(axis, 0);
    EXPECT_GE(tight.radius, measured) << name;
    EXPECT_LT(tight.radius, loose.radius) << name;
    std::printf("%s: tight disc on the axis %.5f of the region's radius (the bounds' %.5f); %d of %d cells with "
                "an off-axis pair of cutting discs\n", name, tight.radius / measured, loose.radius / measured, pairs, cells);
    return tight.radius / measured;
}

// Ctrl-C while the tight discs are measured (their ends on every hardware thread): the reporter's
// exception reaches the caller once the other threads have stopped, as it did from one thread (an
// exception leaving a thread that others still run alongside would end the program).
TEST(PupilBounds, StoppingWhileTightDiscsAreMeasuredThrowsToTheCaller)
{
    struct Stop {};
    const Prescription lens = laikin_wide_angle(3.5);
    const std::shared_ptr<const MainLens> traced = make_prescription_lens(lens, 0, true);
    int tight_reports = 0, after_stop = 0;
    bool stopped = false;
    {
        ScopedSetupReporter reporter([&](const char* step, int done, int) {
            if (std::string(step) != "tight pupil bounds")
                return;
            if (stopped)
                ++after_stop;
            ++tight_reports;
            if (done >= 20 && !stopped) {
                stopped = true;
                throw Stop{};
            }
        });
        EXPECT_THROW(PupilBounds(lens, *traced, -40, true), Stop);
    }
    EXPECT_TRUE(stopped);
    EXPECT_EQ(after_stop, 0);  // nothing reported once stopped
    EXPECT_GE(tight_reports, 2);
}

TEST(PupilBounds, TightDiscsHoldEveryPassingRayAndAreTight)
{
    // On the axis the region is a disc (the lens is one of revolution), and the tight disc may exceed
    // it only by the span margin (1.0001) and the chord lines' apex between two of the 512
    // directions (cos(pi / 512) / cos(2 pi / 512) = 1 + 5.6e-5 on a circle), 1.00016 together: the
    // first span's extents are linear between measured ends like every other span's (its end beyond
    // the axis is the mirror image of its far end). The double Gauss, whose region moves by some
    // 15 um across that span, was at 1.0013 while the first span was one disc holding both ends'.
    const double on_axis = 1.0002;
    EXPECT_LT(expect_tight_discs_hold("Laikin f/3.5, array 40 mm behind", laikin_wide_angle(3.5), -40), on_axis);
    EXPECT_LT(expect_tight_discs_hold("triplet, array 37 mm behind", vignetting_triplet(), -37), on_axis);
    // The catalogue's other lenses, with the array where the benchmark's cameras focused at 2.5 m
    // put it (BENCHMARKS.md, "Samples where light passes").
    EXPECT_LT(expect_tight_discs_hold("double Gauss f/2.1", catalogue_lens("double_gauss_50mm_tronnier_f2.dat", 2.1), -37.13),
              on_axis);
    int fisheye_pairs = 0;
    EXPECT_LT(expect_tight_discs_hold("fisheye f/4", catalogue_lens("fisheye_10mm_muller_f4.dat", 4), -23.20, &fisheye_pairs),
              on_axis);
    EXPECT_GT(fisheye_pairs, 10);  // its cat's eyes off the axis take the off-axis pair (the others may not)
    EXPECT_LT(expect_tight_discs_hold("telephoto f/5.6", catalogue_lens("telephoto_250mm_sigler_f5.6.dat", 5.6), -133.81),
              on_axis);
}

} // namespace
} // namespace plenoptic
