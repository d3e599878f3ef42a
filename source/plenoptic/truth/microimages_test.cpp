// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the microimage ground truth: behind an ideal thin lens every microimage is the exit
// pupil's disc (radius A/2 d/D) about the lattice centre, so the centroid and the lit fraction
// have closed forms; behind a vignetting prescription the polar integration must agree with a
// brute-force count of lit sensor points; the lattice fit must recover a lattice it was given.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/truth/microimages.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/core/sampling.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {


using test::plenoptic_camera;

// The same microimage, bit for bit (the same lens's, from two runs).
void expect_same_microimage(const MicroimageTruth& a, const MicroimageTruth& b)
{
    EXPECT_EQ(a.u_px, b.u_px);
    EXPECT_EQ(a.v_px, b.v_px);
    EXPECT_EQ(a.lit_fraction, b.lit_fraction);
}

struct ClosedFormCase {
    GridType grid;
    double micro_focal_mm;  // 0: pinholes
};

TEST(MicroimageTruth, ThinLensMicroimagesAreThePupilDiscAboutTheLatticeCentres)
{
    // F = 50 mm at f/8 (A = 6.25 mm), D = 52 mm, d = 2 mm, pitch 0.5 mm, 10 um pixels: discs of
    // radius A/2 d/D = 0.1202 mm (12 px) inside cells of 0.519 mm on the sensor.
    const double A = 50.0 / 8, D = 52, d = 2, p = 0.5, pixel = 0.01;
    for (const ClosedFormCase& c : {ClosedFormCase{GridType::Rectangular, 0}, ClosedFormCase{GridType::Hexagonal, 0},
                                    ClosedFormCase{GridType::Hexagonal, 2}, ClosedFormCase{GridType::Rectangular, 1.5}}) {
        CameraParams params = plenoptic_camera(c.grid, p, c.micro_focal_mm, d, 50, 8, D);
        params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = pixel;
        const PlenopticCamera m = make_camera(params);
        const int W = 161, H = 121;
        const std::vector<MicroimageTruth> truth = microimage_truth(with_film(m, W, H), default_microimage_options());
        ASSERT_GE(truth.size(), 6u);
        const double radius_px = 0.5 * A * d / D / pixel;
        const double cell_mm = c.grid == GridType::Hexagonal ? std::sqrt(3.0) / 2 * p * p : p * p;
        const double cell_px = cell_mm * std::pow((D + d) / D, 2) / (pixel * pixel);
        const double fraction = kPi * radius_px * radius_px / cell_px;
        for (const MicroimageTruth& t : truth) {
            double u, v;
            const MicroimageCentre centre_u = microimage_centre_px(with_film(m, W, H), t.lens);
            ASSERT_TRUE(centre_u.valid);
            u = centre_u.u;
            v = centre_u.v;
            ASSERT_TRUE(t.lit);
            EXPECT_NEAR(t.u_px, u, 1e-3) << t.lens.k << "," << t.lens.l;
            EXPECT_NEAR(t.v_px, v, 1e-3) << t.lens.k << "," << t.lens.l;
            EXPECT_NEAR(t.lit_fraction, fraction, 1e-4 * fraction) << t.lens.k << "," << t.lens.l;
            EXPECT_TRUE(u >= -0.5 && u < W - 0.5 && v >= -0.5 && v < H - 0.5);
        }
        // Every lattice centre in the picture is listed: count them independently.
        int inside = 0;
        for (int l = -40; l <= 40; ++l)
            for (int k = -40; k <= 40; ++k) {
                const MicroimageCentre c = microimage_centre_px(with_film(m, W, H), LensIndex{k, l});
                if (c.valid && c.u >= -0.5 && c.u < W - 0.5 && c.v >= -0.5 && c.v < H - 0.5)
                    ++inside;
            }
        EXPECT_EQ(int(truth.size()), inside);
        // An ideal lens: the centres are the metadata's lattice.
        const LatticeFit fit = fit_microimage_lattice(m, truth);
        ASSERT_TRUE(fit.valid);
        EXPECT_LT(fit.max_residual_px, 1e-3);
        const MicroimageLattice lattice = microimage_lattice(with_film(m, W, H));
        for (int i = 0; i < 2; ++i) {
            EXPECT_NEAR(fit.origin_px[i], lattice.origin_px[i], 1e-3);
            EXPECT_NEAR(fit.basis_a_px[i], lattice.basis_a_px[i], 1e-4);
            EXPECT_NEAR(fit.basis_b_px[i], lattice.basis_b_px[i], 1e-4);
        }
    }
}

using test::vignetting_triplet;

// The vignetting triplet focused at 3 m in front of 2.5 mm pinhole microlenses 8.5 mm from a
// sensor of 0.5 mm pixels: cat's-eye microimages towards the corners.
CameraParams triplet_pinholes_camera()
{
    const Prescription lens = vignetting_triplet();
    CameraParams params = plenoptic_camera(GridType::Rectangular, 2.5, 0, 8.5, 50, 4,
                                           paraxial_image_distance(lens, 3000).mm);
    test::use_prescription(&params, lens);
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.5;
    return params;
}

TEST(MicroimageTruth, CatsEyesAgreeWithABruteForceCount)
{
    ASSERT_TRUE(paraxial_image_distance(vignetting_triplet(), 3000).real);
    const CameraParams params = triplet_pinholes_camera();
    const PlenopticCamera m = make_camera(params);
    ASSERT_EQ(test::lens_kind(m), "prescription");
    const int W = 120, H = 120;
    const std::vector<MicroimageTruth> truth = microimage_truth(with_film(m, W, H), default_microimage_options());
    ASSERT_FALSE(truth.empty());
    // Brute force: every point of a fine grid around a lens's lattice centre, the renderer's ray
    // through the lens's pinhole (generate_ray takes corner-convention pixels).
    const LensIndex chosen[] = {{0, 0}, {9, 0}, {-9, 9}, {9, -9}};
    double areas[4], truth_fraction[4];
    for (int c = 0; c < 4; ++c) {
        const LensIndex want = chosen[c];
        const MicroimageTruth* found = nullptr;
        for (const MicroimageTruth& t : truth)
            if (t.lens == want)
                found = &t;
        ASSERT_NE(found, nullptr) << want.k << "," << want.l;
        ASSERT_TRUE(found->lit);
        double u0, v0;
        const MicroimageCentre centre_u0 = microimage_centre_px(with_film(m, W, H), want);
        ASSERT_TRUE(centre_u0.valid);
        u0 = centre_u0.u;
        v0 = centre_u0.v;
        const int n = 600;
        const double half = 6, step = 2 * half / n;
        double count = 0, su = 0, sv = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double u = u0 - half + (i + 0.5) * step, v = v0 - half + (j + 0.5) * step;
                OpticsRay ray;
                if (!(ray = generate_ray(with_film(m, W, H), 0, 0, CameraSample{u + 0.5, v + 0.5, 0.5, 0.5}, &want)).passed)
                    continue;
                count += 1;
                su += u;
                sv += v;
            }
        ASSERT_GT(count, 0);
        EXPECT_NEAR(found->u_px, su / count, 0.01) << want.k << "," << want.l;
        EXPECT_NEAR(found->v_px, sv / count, 0.01) << want.k << "," << want.l;
        areas[c] = count * step * step;
        truth_fraction[c] = found->lit_fraction;
    }
    // The lit fraction is the area over the cell's projected area, the same for every lens up to
    // the projection's small change over the field: compare through the ratio to the centre lens
    // (grid error about perimeter * step / area).
    for (int c = 1; c < 4; ++c)
        EXPECT_NEAR(truth_fraction[c] / truth_fraction[0], areas[c] / areas[0], 0.005) << c;
    // The corners are cat's eyes: far less light than the centre.
    EXPECT_LT(areas[2] / areas[0], 0.8);
    EXPECT_LT(areas[3] / areas[0], 0.8);
}

TEST(MicroimageTruth, ThinMicrolensesConvergeInApertureAndThreadsDoNotMatter)
{
    // The triplet with a hexagonal array of thin microlenses (plenoptic 1.0: d = f).
    const Prescription lens = vignetting_triplet();
    const ImageDistance focus = paraxial_image_distance(lens, 3000);
    ASSERT_TRUE(focus.real);
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 2.5, 8.5, 8.5, 50, 4, focus.mm);
    test::use_prescription(&params, lens);
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.5;
    const PlenopticCamera m = make_camera(params);
    const int W = 120, H = 120;
    MicroimageOptions coarse = default_microimage_options(), fine = coarse, one_thread = coarse;
    fine.aperture_points = 8;
    one_thread.threads = 1;
    coarse.threads = 3;
    const std::vector<MicroimageTruth> a = microimage_truth(with_film(m, W, H), coarse);
    const std::vector<MicroimageTruth> b = microimage_truth(with_film(m, W, H), fine);
    const std::vector<MicroimageTruth> c = microimage_truth(with_film(m, W, H), one_thread);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(a.size(), c.size());
    double worst_px = 0, worst_fraction = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_TRUE(a[i].lens == c[i].lens && a[i].lit == c[i].lit);
        EXPECT_EQ(a[i].u_px, c[i].u_px);  // bit for bit
        EXPECT_EQ(a[i].lit_fraction, c[i].lit_fraction);
        if (!a[i].lit || !b[i].lit || b[i].lit_fraction < 0.05)
            continue;
        worst_px = std::max(worst_px, std::hypot(a[i].u_px - b[i].u_px, a[i].v_px - b[i].v_px));
        worst_fraction = std::max(worst_fraction, std::fabs(a[i].lit_fraction - b[i].lit_fraction));
    }
    // Seen: 3 x 3 points within 0.0072 px of 8 x 8 (2 x 2: 0.020 px, 1: 0.041 px), fractions within 0.001.
    EXPECT_LT(worst_px, 0.015);
    EXPECT_LT(worst_fraction, 0.005);
}

// Seeking each boundary near the previous lenses' (the default) against measuring every lens from
// scratch (the reference): the same lenses, the same centres within 0.001 px and lit fractions
// within 1e-4, behind the vignetting triplet (cat's eyes, thin and pinhole microlenses, rows of
// many lenses; an array with manufacturing errors) and behind an ideal lens; and the same bits
// whatever the thread count.
TEST(MicroimageTruth, ReusingNeighboursAgreesWithEveryLensFromScratch)
{
    const Prescription lens = vignetting_triplet();
    const ImageDistance focus = paraxial_image_distance(lens, 3000);
    ASSERT_TRUE(focus.real);
    CameraParams thin = plenoptic_camera(GridType::Hexagonal, 1.0, 3.4, 3.4, 50, 4, focus.mm);
    test::use_prescription(&thin, lens);
    thin.sensor.pixel_size_mm[0] = thin.sensor.pixel_size_mm[1] = 0.1;
    CameraParams ideal = plenoptic_camera(GridType::Rectangular, 0.2, 0.8, 0.8, 50, 8, 52);
    ideal.sensor.pixel_size_mm[0] = ideal.sensor.pixel_size_mm[1] = 0.01;
    struct Case {
        const char* name;
        PlenopticCamera camera;
    };
    // The same with manufacturing errors: each lens displaced (0.01 mm, a tenth of a pixel), its
    // focal length scaled (2 %) and tilted (up to 1 degree), so neighbours' boundaries differ.
    CameraParams jittered = thin;
    jittered.array.has_errors = true;
    jittered.array.errors.position_sd_mm = 0.01;
    jittered.array.errors.focal_sd = 0.02;
    jittered.array.errors.rotation_deg = 1;
    jittered.array.errors.seed = 7;
    const Case cases[] = {{"triplet, thin microlenses", with_film(make_camera(thin), 360, 300)},
                          {"triplet, thin microlenses with errors", with_film(make_camera(jittered), 360, 300)},
                          {"triplet, pinholes", with_film(make_camera(triplet_pinholes_camera()), 120, 120)},
                          {"ideal lens", with_film(make_camera(ideal), 401, 301)}};
    for (const Case& c : cases) {
        MicroimageOptions fast = default_microimage_options(), reference = fast, one_thread = fast;
        ASSERT_TRUE(fast.reuse_neighbours);
        reference.reuse_neighbours = false;
        fast.threads = 3;
        one_thread.threads = 1;
        const std::vector<MicroimageTruth> a = microimage_truth(c.camera, fast);
        const std::vector<MicroimageTruth> b = microimage_truth(c.camera, reference);
        const std::vector<MicroimageTruth> d = microimage_truth(c.camera, one_thread);
        ASSERT_EQ(a.size(), b.size()) << c.name;
        ASSERT_EQ(a.size(), d.size()) << c.name;
        ASSERT_GT(a.size(), 100u) << c.name;
        double worst_px = 0, worst_fraction = 0;
        int lit = 0;
        for (std::size_t i = 0; i < a.size(); ++i) {
            ASSERT_TRUE(a[i].lens == b[i].lens && a[i].lit == b[i].lit) << c.name << " " << i;
            ASSERT_TRUE(a[i].lens == d[i].lens && a[i].lit == d[i].lit) << c.name << " " << i;
            expect_same_microimage(a[i], d[i]);
            worst_fraction = std::max(worst_fraction, std::fabs(a[i].lit_fraction - b[i].lit_fraction));
            if (!a[i].lit)
                continue;
            ++lit;
            worst_px = std::max(worst_px, std::max(std::fabs(a[i].u_px - b[i].u_px), std::fabs(a[i].v_px - b[i].v_px)));
        }
        EXPECT_GT(lit, 100) << c.name;
        EXPECT_LT(worst_px, 1e-3) << c.name;
        EXPECT_LT(worst_fraction, 1e-4) << c.name;
        std::printf("%s: %zu lenses, largest difference %.2g px, lit fraction %.2g\n", c.name, a.size(), worst_px,
                    worst_fraction);
    }
}

// The harder arrays: refracting microlenses (24 x 24 cell points a lens, whose regions near the
// cell's edge are cut by the cell on the far face of the glass, or empty) and thin microlenses with
// large tilts (3 degrees) besides displacements, focal-length errors and errors along the axis, whose
// regions are stretched unevenly. Seeking each boundary near the previous lenses' must still give
// every lens's centre within 0.001 px and lit fraction within 1e-4 of measuring it from scratch, and
// the same bits whatever the thread count.
TEST(MicroimageTruth, ReusingNeighboursAgreesFromScratchForRefractingAndTiltedLenses)
{
    const Prescription lens = vignetting_triplet();
    const ImageDistance focus = paraxial_image_distance(lens, 3000);
    ASSERT_TRUE(focus.real);
    CameraParams thin = plenoptic_camera(GridType::Hexagonal, 1.0, 3.4, 3.4, 50, 4, focus.mm);
    test::use_prescription(&thin, lens);
    thin.sensor.pixel_size_mm[0] = thin.sensor.pixel_size_mm[1] = 0.1;
    CameraParams tilted = thin;
    tilted.array.has_errors = true;
    tilted.array.errors.position_sd_mm = 0.005;
    tilted.array.errors.position_sd_z_mm = 0.01;
    tilted.array.errors.focal_sd = 0.02;
    tilted.array.errors.rotation_deg = 3;
    tilted.array.errors.seed = 11;
    // Plano-convex caps of the same paraxial focal length (R = f (n - 1)), the curved side towards
    // the scene, the sensor at their back focal distance f - L / n from the flat face.
    CameraParams refracting = thin;
    test::use_refracting_caps(&refracting, 1.7, 1.5, 0.12, 0.2);
    refracting.array.distance_mm = 3.4 - 0.32 / 1.5;
    CameraParams refracting_errors = refracting;
    refracting_errors.array.has_errors = true;
    refracting_errors.array.errors = tilted.array.errors;
    struct Case {
        const char* name;
        PlenopticCamera camera;
        std::size_t lenses;
    };
    const Case cases[] = {{"thin microlenses, tilted 3 degrees", with_film(make_camera(tilted), 360, 300), 100},
                          {"refracting microlenses", with_film(make_camera(refracting), 60, 50), 8},
                          {"refracting microlenses with errors", with_film(make_camera(refracting_errors), 60, 50), 8}};
    for (const Case& c : cases) {
        MicroimageOptions fast = default_microimage_options(), reference = fast, one_thread = fast;
        reference.reuse_neighbours = false;
        fast.threads = 3;
        one_thread.threads = 1;
        const std::vector<MicroimageTruth> a = microimage_truth(c.camera, fast);
        const std::vector<MicroimageTruth> b = microimage_truth(c.camera, reference);
        const std::vector<MicroimageTruth> d = microimage_truth(c.camera, one_thread);
        ASSERT_EQ(a.size(), b.size()) << c.name;
        ASSERT_EQ(a.size(), d.size()) << c.name;
        ASSERT_GE(a.size(), c.lenses) << c.name;
        double worst_px = 0, worst_fraction = 0, smallest = INFINITY, largest = 0;
        std::size_t lit = 0;
        for (std::size_t i = 0; i < a.size(); ++i) {
            ASSERT_TRUE(a[i].lens == b[i].lens && a[i].lit == b[i].lit) << c.name << " " << i;
            ASSERT_TRUE(a[i].lens == d[i].lens && a[i].lit == d[i].lit) << c.name << " " << i;
            expect_same_microimage(a[i], d[i]);
            worst_fraction = std::max(worst_fraction, std::fabs(a[i].lit_fraction - b[i].lit_fraction));
            if (!a[i].lit)
                continue;
            ++lit;
            smallest = std::min(smallest, a[i].lit_fraction);
            largest = std::max(largest, a[i].lit_fraction);
            worst_px = std::max(worst_px, std::max(std::fabs(a[i].u_px - b[i].u_px), std::fabs(a[i].v_px - b[i].v_px)));
        }
        EXPECT_GE(lit, c.lenses) << c.name;
        EXPECT_LT(worst_px, 1e-3) << c.name;
        EXPECT_LT(worst_fraction, 1e-4) << c.name;
        // Real microimages, not empty ones agreeing: lit fractions of whole cells' light.
        EXPECT_GT(smallest, 0.05) << c.name;
        EXPECT_LT(largest, 1.5) << c.name;
        std::printf("%s: %zu lenses, largest difference %.2g px, lit fraction %.2g (lit fractions %.3f to %.3f)\n",
                    c.name, a.size(), worst_px, worst_fraction, smallest, largest);
    }
}

// Refracting microlenses behind the vignetting triplet focused at 3000 mm: hexagonal, pitch 0.25 mm,
// pixels of 0.025 mm, caps of R = 0.425 mm (n 1.5, 0.03 mm on 0.05 mm of substrate, the curved side
// to the scene) whose paraxial focal length, 0.85 mm, is the array's f; the sensor at their back
// focal distance, f - L / n from the flat back (curved side to the sensor: f from the caps' vertex
// plane, whose principal plane is that vertex).
CameraParams refracting_behind_triplet()
{
    const Prescription lens = vignetting_triplet();
    const ImageDistance focus = paraxial_image_distance(lens, 3000);
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 0.25, 0.85, 0.85, 50, 4, focus.mm);
    test::use_prescription(&params, lens);
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.025;
    test::use_refracting_caps(&params, 0.425, 1.5, 0.03, 0.05);
    params.array.distance_mm = 0.85 - 0.08 / 1.5;
    return params;
}

// `count` indices below `size` drawn from `seed` (a fixed generator: the same lenses on every run).
std::vector<std::size_t> drawn_indices(std::size_t size, int count, std::uint64_t seed)
{
    std::vector<std::size_t> which;
    for (int i = 0; i < count; ++i) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        which.push_back(std::size_t((seed >> 33) % size));
    }
    return which;
}

// The truth's lenses `which` (indices into `truth`) against each of them measured
// (measured_microimages, anchor_step 0: no anchors): whether each is lit alike, the largest
// difference along either axis (px) over the lit ones and of lit fraction over all, the lit ones'
// lit fractions, and how far their measured microimages lie from their lattice centres.
struct AgainstMeasured {
    bool alike = true;
    std::size_t lit = 0;
    double worst_px = 0, worst_fraction = 0, smallest = INFINITY, largest = 0, spread = 0;
};
AgainstMeasured against_measured(const PlenopticCamera& camera, const std::vector<MicroimageTruth>& truth,
                                 const std::vector<std::size_t>& which, MicroimageOptions options)
{
    std::vector<LensIndex> lenses;
    for (std::size_t i : which)
        lenses.push_back(truth[i].lens);
    options.anchor_step = 0;
    const std::vector<MicroimageTruth> b = measured_microimages(camera, lenses, options);
    AgainstMeasured r;
    r.alike = b.size() == which.size();
    for (std::size_t n = 0; r.alike && n < which.size(); ++n) {
        const MicroimageTruth& x = truth[which[n]];
        r.alike = x.lens == b[n].lens && x.lit == b[n].lit;
        r.worst_fraction = std::max(r.worst_fraction, std::fabs(x.lit_fraction - b[n].lit_fraction));
        if (!x.lit)
            continue;
        ++r.lit;
        r.smallest = std::min(r.smallest, x.lit_fraction);
        r.largest = std::max(r.largest, x.lit_fraction);
        r.worst_px = std::max(r.worst_px, std::max(std::fabs(x.u_px - b[n].u_px), std::fabs(x.v_px - b[n].v_px)));
        const MicroimageCentre centre = microimage_centre_px(camera, x.lens);
        r.spread = std::max(r.spread, std::hypot(b[n].u_px - centre.u, b[n].v_px - centre.v));
    }
    return r;
}

// Refracting microlenses on an array without errors: the lenses between anchors (every fourth lens
// of every fourth row here) are interpolated. Every lens checked must agree with measuring it
// (measured_microimages, what anchor_step 0 gives) within 0.001 px and 1e-4 of lit fraction, with
// either side of the caps towards the scene, over a field whose corners the triplet vignettes; the
// answer is the same bits on 1 and 3 threads. With manufacturing errors on a picture too small for
// anchors every lens is measured: the same bits as anchor_step 0.
TEST(MicroimageTruth, RefractingLensesBetweenAnchorsAgreeWithMeasuringThem)
{
    ASSERT_TRUE(paraxial_image_distance(vignetting_triplet(), 3000).real);
    // Lenses a quarter of the other tests' (pitch 0.25 mm, 10 pixels of 0.025 mm), so that anchors
    // four lenses apart are 1 mm apart in the triplet's field, as sixteen Lytro-class lenses are a
    // thirtieth of that camera's field; the picture (240 x 208 pixels, 6 x 5.2 mm) lies towards
    // the corner of the field, where the triplet vignettes.
    CameraParams scene_side = refracting_behind_triplet();
    scene_side.sensor.offset_mm[0] = 9;
    scene_side.sensor.offset_mm[1] = 7;
    // Without baffles light that leaves a cell in the glass goes on in the neighbour's; with caps
    // towards the scene thin lobes of it, apart from the lens's own light, are counted at the cell
    // points near the cell's edge whose own light is gone, and the lenses whose anchors count any
    // are measured. With baffles (no such light) most lenses are interpolated.
    CameraParams scene_baffled = scene_side;
    scene_baffled.array.baffles = true;
    CameraParams sensor_baffled = scene_baffled;
    sensor_baffled.array.refracting.curved_towards_scene = false;
    sensor_baffled.array.distance_mm = 0.85;
    struct Case {
        const char* name;
        CameraParams params;
        bool mostly_interpolated;
    };
    const Case cases[] = {{"caps towards the scene", scene_side, false},
                          {"caps towards the scene, baffles", scene_baffled, true},
                          {"caps towards the sensor, baffles", sensor_baffled, true}};
    for (const Case& c : cases) {
        const PlenopticCamera camera = with_film(make_camera(c.params), 240, 208);
        MicroimageOptions fast = default_microimage_options(), one_thread = fast;
        fast.anchor_step = one_thread.anchor_step = 4;
        fast.threads = 3;
        one_thread.threads = 1;
        MicroimageWork work;
        const std::vector<MicroimageTruth> a = microimage_truth(camera, fast, MicroimageProgress(), MicroimageCancel(),
                                                                nullptr, &work);
        ASSERT_GE(a.size(), 500u) << c.name;
        if (&c == &cases[0]) {
            // The thread count does not matter (one orientation suffices: the path is the same).
            MicroimageWork work_one;
            const std::vector<MicroimageTruth> d = microimage_truth(camera, one_thread, MicroimageProgress(),
                                                                    MicroimageCancel(), nullptr, &work_one);
            ASSERT_EQ(a.size(), d.size()) << c.name;
            for (std::size_t i = 0; i < a.size(); ++i) {
                ASSERT_TRUE(a[i].lens == d[i].lens && a[i].lit == d[i].lit) << c.name << " " << i;
                expect_same_microimage(a[i], d[i]);
            }
            EXPECT_EQ(work.interpolated, work_one.interpolated) << c.name;
        }
        // Most lenses interpolated, and the anchors far fewer than the lenses.
        EXPECT_EQ(work.interpolated + work.measured, a.size()) << c.name;
        if (c.mostly_interpolated) {
            EXPECT_GT(work.interpolated, a.size() / 2) << c.name;
        }
        EXPECT_LT(4 * work.anchors, a.size()) << c.name;
        // Lenses drawn across the picture, every lens of its first row (the picture's edge, where
        // the stencils are one-sided) and the last lens (a corner), each measured.
        std::vector<std::size_t> which = drawn_indices(a.size(), 24, 12345);
        for (std::size_t i = 0; i < a.size() && a[i].lens.l == a[0].lens.l; ++i)
            which.push_back(i);
        which.push_back(a.size() - 1);
        const AgainstMeasured r = against_measured(camera, a, which, one_thread);
        ASSERT_TRUE(r.alike) << c.name;
        EXPECT_LT(r.worst_px, 1e-3) << c.name;
        EXPECT_LT(r.worst_fraction, 1e-4) << c.name;
        EXPECT_GT(r.smallest, 0.05) << c.name;
        std::printf("%s: %zu lenses, %zu anchors, %zu interpolated, %zu measured; %zu checked: largest difference "
                    "%.2g px, lit fraction %.2g (lit fractions %.3f to %.3f)\n",
                    c.name, a.size(), work.anchors, work.interpolated, work.measured, which.size(), r.worst_px,
                    r.worst_fraction, r.smallest, r.largest);
    }
    // With errors on a picture too small for anchors: every lens measured, as with anchor_step 0.
    CameraParams errors = scene_side;
    errors.array.has_errors = true;
    errors.array.errors.position_sd_mm = 0.005;
    errors.array.errors.focal_sd = 0.02;
    errors.array.errors.rotation_deg = 1;
    errors.array.errors.seed = 5;
    const PlenopticCamera camera = with_film(make_camera(errors), 60, 50);
    MicroimageOptions anchored = default_microimage_options(), every = anchored;
    anchored.anchor_step = 4;
    every.anchor_step = 0;
    MicroimageWork work;
    const std::vector<MicroimageTruth> a = microimage_truth(camera, anchored, MicroimageProgress(), MicroimageCancel(),
                                                            nullptr, &work);
    const std::vector<MicroimageTruth> b = microimage_truth(camera, every);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(work.anchors, 0u);
    EXPECT_EQ(work.measured, a.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_TRUE(a[i].lens == b[i].lens && a[i].lit == b[i].lit);
        expect_same_microimage(a[i], b[i]);
    }
}

// Refracting microlenses with manufacturing errors, corrected (MicroimageOptions::error_anchor_step):
// each lens is the ideal lens interpolated where it sits, corrected for its own dz, focal length and
// tilt and for its neighbours' displacements by differences measured at Jacobian anchors (here
// every fourth lens of every fourth row, on an array centred on the axis: measured in one quarter,
// mirrored to the others). Errors scaled to this test's pitch as 0.5 um, 2 % and 0.5 degrees are to
// a Lytro-class array's 20 um. Against each lens measured (anchor_step 0), over lenses drawn across
// the picture and its first row:
// - focal lengths and tilts (3 % and 1 degree here, which move the microimages by some 0.04
//   px): within 1e-3 px and 1e-4 of lit fraction, the same bits on 1 and 3 threads; a term left
//   out, or mirrored the wrong way, fails;
// - displacements too: within 0.03 px and 0.015 of lit fraction (the neighbours' displacements cut
//   lit parts of these cells, kinks the second-order terms do not follow: what the option's
//   documentation states).
TEST(MicroimageTruth, RefractingLensesWithErrorsAreCorrectedIdealLenses)
{
    struct Case {
        const char* name;
        double position_sd_mm, focal_sd, rotation_deg;
        double within_px, within_fraction;
    };
    const Case cases[] = {{"focal lengths and tilts", 0, 0.03, 1, 1e-3, 1e-4},
                          {"displacements, focal lengths and tilts", 0.00625, 0.02, 0.5, 0.03, 0.015}};
    for (const Case& c : cases) {
        CameraParams params = refracting_behind_triplet();
        params.array.has_errors = true;
        params.array.errors.position_sd_mm = c.position_sd_mm;
        params.array.errors.focal_sd = c.focal_sd;
        params.array.errors.rotation_deg = c.rotation_deg;
        params.array.errors.seed = 11;
        const PlenopticCamera camera = with_film(make_camera(params), 200, 180);
        MicroimageOptions options = default_microimage_options();
        options.anchor_step = 4;
        options.error_anchor_step = 4;
        options.refracting_points = 12;
        options.threads = 3;
        MicroimageWork work;
        const std::vector<MicroimageTruth> a =
            microimage_truth(camera, options, MicroimageProgress(), MicroimageCancel(), nullptr, &work);
        ASSERT_GE(a.size(), 300u) << c.name;
        EXPECT_GT(work.corrected, a.size() / 3) << c.name;
        EXPECT_GT(work.error_anchors, 0u) << c.name;
        EXPECT_EQ(work.interpolated + work.measured, a.size()) << c.name;
        MicroimageOptions one_thread = options;
        one_thread.threads = 1;
        if (&c == &cases[0]) {
            const std::vector<MicroimageTruth> d = microimage_truth(camera, one_thread);
            ASSERT_EQ(a.size(), d.size());
            for (std::size_t i = 0; i < a.size(); ++i) {
                ASSERT_TRUE(a[i].lens == d[i].lens && a[i].lit == d[i].lit) << i;
                expect_same_microimage(a[i], d[i]);
            }
        }
        std::vector<std::size_t> which = drawn_indices(a.size(), 24, 777);
        for (std::size_t i = 0; i < a.size() && a[i].lens.l == a[0].lens.l; ++i)
            which.push_back(i);
        const AgainstMeasured r = against_measured(camera, a, which, one_thread);
        ASSERT_TRUE(r.alike) << c.name;
        EXPECT_LT(r.worst_px, c.within_px) << c.name;
        EXPECT_LT(r.worst_fraction, c.within_fraction) << c.name;
        // What the errors do: the same lenses measured on the ideal array.
        CameraParams ideal_params = params;
        ideal_params.array.has_errors = false;
        const AgainstMeasured moved =
            against_measured(with_film(make_camera(ideal_params), 200, 180), a, which, one_thread);
        EXPECT_GT(moved.worst_px, 10 * c.within_px) << c.name;
        std::printf("%s: %zu lenses, %zu anchors, %zu Jacobian anchors (quarter lenses), %zu corrected, %zu "
                    "measured; %zu checked: largest difference %.3g px, lit fraction %.3g (from the ideal "
                    "array's: %.3g px, %.3g)\n",
                    c.name, a.size(), work.anchors, work.error_anchors, work.corrected, work.measured, which.size(),
                    r.worst_px, r.worst_fraction, moved.worst_px, moved.worst_fraction);
    }
}

// Refracting microlenses on an array whose lens (0, 0) sits on the axis: the camera, and the truth's
// own rule, map onto themselves under the mirrors in the array's x and y axes, so the truth measures
// the lenses of the quarter x >= 0, y >= 0 and gives each other lens its image's microimage,
// mirrored (MicroimageOptions::symmetry). Four lenses that are each other's mirror images, found
// here from the lattice's geometry, behind the vignetting triplet where it cuts the microimages:
// (1) their microimages as the truth gives them are each other's mirror images, to rounding;
// (2) each lens measured where it is (symmetry off) gives the same microimage within 1e-6 px and
// 1e-9 of lit fraction (the rule is symmetric too), where a lens's offset from its lattice centre,
// which a wrong mirror would turn, is some 0.4 px; (3) the same with the array turned about the
// axis by 90 degrees (its mirrors the sensor's y and x); (4) an array moved off the axis, or turned
// by 10 degrees (whose mirrors are not the rule's: it lays its grids and directions out in pixels),
// is measured lens by lens (the option changes nothing).
TEST(MicroimageTruth, RefractingMicroimagesAreMirrorImagesOfTheirQuarterLenses)
{
    ASSERT_TRUE(paraxial_image_distance(vignetting_triplet(), 3000).real);
    CameraParams params = refracting_behind_triplet();
    params.array.baffles = true;
    const double turn_deg[2] = {0, 90};
    for (double turned : turn_deg) {
        CameraParams p = params;
        p.array.rotate_deg[2] = turned;
        const PlenopticCamera camera = with_film(make_camera(p), 40, 40);
        const GridType grid = GridType::Hexagonal;
        const double pitch = 0.25, psi = turned * kPi / 180;
        // A lens on an odd row (its mirror in x is not its own column), 9.6 mm from the axis, and its
        // mirror images in the array's own frame.
        const LensIndex seed{37, 11};
        const Vec2 c = lens_centre(grid, pitch, seed);
        std::vector<LensIndex> images;
        const double signs[4][2] = {{1, 1}, {-1, 1}, {1, -1}, {-1, -1}};
        for (const auto& sign : signs) {
            const LensIndex l = nearest_lens(grid, pitch, sign[0] * c.x, sign[1] * c.y);
            const Vec2 back = lens_centre(grid, pitch, l);
            ASSERT_NEAR(back.x, sign[0] * c.x, 1e-12);
            ASSERT_NEAR(back.y, sign[1] * c.y, 1e-12);
            images.push_back(l);
        }
        MicroimageOptions symmetric = default_microimage_options();
        symmetric.threads = 2;
        MicroimageOptions each = symmetric;
        each.symmetry = false;
        const std::vector<MicroimageTruth> a = measured_microimages(camera, images, symmetric);
        const std::vector<MicroimageTruth> b = measured_microimages(camera, images, each);
        ASSERT_EQ(a.size(), images.size());
        ASSERT_EQ(b.size(), images.size());
        // A centroid in the array's frame (the optics frame turned back by psi).
        auto local = [&](const MicroimageTruth& t) {
            const Vec3 q = camera.sensor.point(t.u_px + 0.5, t.v_px + 0.5);
            return Vec2{std::cos(psi) * q.x + std::sin(psi) * q.y, -std::sin(psi) * q.x + std::cos(psi) * q.y};
        };
        ASSERT_TRUE(a[0].lit);
        const Vec2 s0 = local(a[0]);
        double worst_map = 0, worst_each = 0, worst_fraction = 0, spread = 0;
        for (std::size_t i = 0; i < images.size(); ++i) {
            ASSERT_TRUE(a[i].lit && b[i].lit) << i;
            const Vec2 got = local(a[i]);
            worst_map = std::max(worst_map, std::hypot(got.x - signs[i][0] * s0.x, got.y - signs[i][1] * s0.y) / 0.025);
            EXPECT_EQ(a[i].lit_fraction, a[0].lit_fraction) << i;
            worst_each = std::max(worst_each, std::max(std::fabs(a[i].u_px - b[i].u_px), std::fabs(a[i].v_px - b[i].v_px)));
            worst_fraction = std::max(worst_fraction, std::fabs(a[i].lit_fraction - b[i].lit_fraction));
            // How far the microimage lies from the lens's lattice centre: what a wrong mirror would move.
            const MicroimageCentre centre = microimage_centre_px(camera, images[i]);
            spread = std::max(spread, std::hypot(a[i].u_px - centre.u, a[i].v_px - centre.v));
        }
        EXPECT_LT(worst_map, 1e-9) << turned;
        EXPECT_LT(worst_each, 1e-6) << turned;
        EXPECT_LT(worst_fraction, 1e-9) << turned;
        EXPECT_GT(spread, 0.1) << turned;
        std::printf("array turned %g deg: 4 mirror images, mirrored to %.2g px; measured where they are: within %.2g px "
                    "and %.2g of lit fraction (offsets from the lattice up to %.3g px)\n",
                    turned, worst_map, worst_each, worst_fraction, spread);
    }
    // Off the axis, or turned by 10 degrees: no symmetry used.
    CameraParams moved = params, turned = params;
    moved.array.translate_mm[0] = 0.08;
    turned.array.rotate_deg[2] = 10;
    for (const CameraParams& p : {moved, turned}) {
        const PlenopticCamera camera = with_film(make_camera(p), 40, 40);
        MicroimageOptions with = default_microimage_options(), without = with;
        without.symmetry = false;
        const std::vector<LensIndex> lenses = {LensIndex{37, 11}, LensIndex{-38, 11}, LensIndex{37, -11}};
        const std::vector<MicroimageTruth> x = measured_microimages(camera, lenses, with);
        const std::vector<MicroimageTruth> y = measured_microimages(camera, lenses, without);
        ASSERT_EQ(x.size(), y.size());
        for (std::size_t i = 0; i < x.size(); ++i) {
            expect_same_microimage(x[i], y[i]);
        }
    }
}

// Refracting microlenses on an ideal array turned about the axis by other than a multiple of 90
// degrees, or moved off it: the anchors are measured in the same array turned back onto the axis
// (where the mirrors hold), each lens interpolated at the point it occupies there and turned back
// (Canonical). Against each lens measured where it is, in the camera as it is (an answer that
// uses neither the turn nor the anchors): the array moved across by a fraction of its pitch agrees
// within the interpolation's 1e-3 px and 1e-4 of lit fraction; turned, within the rule's own
// error, since the rule's directions are laid out in pixels and do not turn with the array (a
// lens and its image turned by 10 degrees, each measured, differ by that much). A wrong turn or
// shift would move centroids by tenths of a pixel: lenses' offsets from their lattice points
// reach 0.4 px here, and one lens pitch is 10 px.
TEST(MicroimageTruth, TurnedOrMovedRefractingArraysTakeTheirAnchorsOnTheAxis)
{
    ASSERT_TRUE(paraxial_image_distance(vignetting_triplet(), 3000).real);
    CameraParams base = refracting_behind_triplet();
    base.sensor.offset_mm[0] = 9;
    base.sensor.offset_mm[1] = 7;
    base.array.baffles = true;
    struct Case {
        const char* name;
        double turn_deg, shift_mm[2];
        double tolerance_px, tolerance_fraction;
    };
    const Case cases[] = {{"moved", 0, {0.08, 0.05}, 1e-3, 1e-4},
                          {"turned 10 degrees", 10, {0, 0}, 2e-3, 3e-4},
                          {"turned 0.2 degrees and moved", 0.2, {-0.11, 0.03}, 2e-3, 3e-4}};
    for (const Case& c : cases) {
        CameraParams p = base;
        p.array.rotate_deg[2] = c.turn_deg;
        p.array.translate_mm[0] = c.shift_mm[0];
        p.array.translate_mm[1] = c.shift_mm[1];
        const PlenopticCamera camera = with_film(make_camera(p), 240, 208);
        MicroimageOptions options = default_microimage_options();
        options.anchor_step = 4;
        options.threads = 2;
        MicroimageWork work;
        const std::vector<MicroimageTruth> a = microimage_truth(camera, options, MicroimageProgress(),
                                                                MicroimageCancel(), nullptr, &work);
        ASSERT_GE(a.size(), 400u) << c.name;
        EXPECT_GT(work.interpolated, a.size() / 2) << c.name;
        EXPECT_GT(work.quarter_lenses, 0u) << c.name;  // anchors measured on the axis (0 without Canonical)
        // Lenses drawn across the picture and its first and last lens, each measured where it is.
        std::vector<std::size_t> which = drawn_indices(a.size(), 30, 777);
        which.push_back(0);
        which.push_back(a.size() - 1);
        const AgainstMeasured r = against_measured(camera, a, which, options);
        ASSERT_TRUE(r.alike) << c.name;
        EXPECT_GT(r.lit, which.size() / 2) << c.name;
        EXPECT_LT(r.worst_px, c.tolerance_px) << c.name;
        EXPECT_LT(r.worst_fraction, c.tolerance_fraction) << c.name;
        EXPECT_GT(r.spread, 0.1) << c.name;
        std::printf("%s: %zu lenses, %zu anchors (%zu measured on the axis), %zu interpolated, %zu measured; "
                    "%zu checked: largest difference %.2g px, lit fraction %.2g (offsets up to %.2f px)\n",
                    c.name, a.size(), work.anchors, work.quarter_lenses - work.measured, work.interpolated,
                    work.measured, which.size(), r.worst_px, r.worst_fraction, r.spread);
    }
}

TEST(MicroimageTruth, LatticeFitRecoversAGivenLattice)
{
    const PlenopticCamera m = make_camera(plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52));
    // Centres on a known skew lattice, plus a known residual pattern of zero mean that is
    // orthogonal to (1, k_s, l) over the set: +e on even k_s + l, -e on odd, balanced per row.
    const double o[2] = {100.25, 80.5}, a[2] = {14.2, 0.3}, b[2] = {7.1, 12.4};
    std::vector<MicroimageTruth> truth;
    for (int l = -4; l <= 3; ++l)
        for (int ks = -5; ks <= 4; ++ks) {
            const double e = ((ks + l) % 2 == 0) ? 0.05 : -0.05;
            MicroimageTruth t;
            t.lens = from_skew(GridType::Hexagonal, ks, l);
            t.lit = true;
            t.u_px = o[0] + ks * a[0] + l * b[0] + e;
            t.v_px = o[1] + ks * a[1] + l * b[1] - e;
            t.lit_fraction = 1;
            truth.push_back(t);
        }
    MicroimageTruth dark = truth.back();
    dark.lens = from_skew(GridType::Hexagonal, 50, 50);
    dark.lit = false;
    dark.u_px = dark.v_px = 1e9;  // not fitted
    truth.push_back(dark);
    const LatticeFit fit = fit_microimage_lattice(m, truth);
    ASSERT_TRUE(fit.valid);
    EXPECT_EQ(fit.lenses, truth.size() - 1);
    for (int i = 0; i < 2; ++i) {
        EXPECT_NEAR(fit.origin_px[i], o[i], 1e-9);
        EXPECT_NEAR(fit.basis_a_px[i], a[i], 1e-9);
        EXPECT_NEAR(fit.basis_b_px[i], b[i], 1e-9);
    }
    EXPECT_NEAR(fit.rms_residual_px, 0.05 * std::sqrt(2.0), 1e-9);
    EXPECT_NEAR(fit.max_residual_px, 0.05 * std::sqrt(2.0), 1e-9);
    const Vec2 r = lattice_residual(m, fit, truth.front());
    EXPECT_NEAR(std::fabs(r.x), 0.05, 1e-9);
    EXPECT_NEAR(r.x, -r.y, 1e-12);
}

TEST(MicroimageTruth, CancellingStopsAtTheNextLensAndReturnsNothing)
{
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 8, 52);
    params.sensor.pixel_size_mm[0] = params.sensor.pixel_size_mm[1] = 0.01;
    const PlenopticCamera m = with_film(make_camera(params), 401, 301);
    MicroimageOptions options = default_microimage_options();
    options.threads = 2;
    ASSERT_GT(microimage_truth(m, options).size(), 50u);
    int polls = 0;
    std::size_t reports = 0;
    const std::vector<MicroimageTruth> none = microimage_truth(m, options, [&](std::size_t done, std::size_t) { reports = done; }, [&]() { return ++polls > 5; });
    EXPECT_TRUE(none.empty());
    EXPECT_EQ(polls, 6);  // polled before each lens of the calling thread, stopped at the first true
    EXPECT_LT(reports, 50u);
}

// Per channel: the same lenses in the same order; through a lens that does not disperse the
// centres at any wavelength are the d line's exactly, through one that does they move, and by the
// camera at that wavelength's own measure (the truth of a camera made at that wavelength).
TEST(MicroimageTruth, ChannelsAreTheSameLensesMeasuredAtTheirWavelength)
{
    CameraParams params = triplet_pinholes_camera();
    const int W = 80, H = 80;
    const PlenopticCamera plain = with_film(make_camera(params), W, H);
    const PlenopticCamera plain_blue = at_wavelength(plain, 450);
    const std::vector<MicroimageTruth> a = microimage_truth(plain, default_microimage_options());
    const std::vector<MicroimageTruth> b = microimage_truth(plain, default_microimage_options(), MicroimageProgress(),
                                                            MicroimageCancel(), &plain_blue);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].u_px, b[i].u_px);
        EXPECT_EQ(a[i].v_px, b[i].v_px);
    }

    for (LensSurface& s : params.main.prescription.surfaces)
        if (s.ior > 1)
            s.glass.abbe = 25;
    const PlenopticCamera glass = with_film(make_camera(params), W, H);
    const PlenopticCamera blue = at_wavelength(glass, 450);
    const std::vector<MicroimageTruth> d = microimage_truth(glass, default_microimage_options());
    const std::vector<MicroimageTruth> e = microimage_truth(glass, default_microimage_options(), MicroimageProgress(),
                                                            MicroimageCancel(), &blue);
    ASSERT_EQ(d.size(), e.size());
    double largest = 0;
    int lit = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        EXPECT_EQ(d[i].lens.k, e[i].lens.k);
        EXPECT_EQ(d[i].lens.l, e[i].lens.l);
        if (d[i].lit && e[i].lit) {
            largest = std::max(largest, std::hypot(d[i].u_px - e[i].u_px, d[i].v_px - e[i].v_px));
            ++lit;
        }
    }
    EXPECT_GT(lit, 4);
    EXPECT_GT(largest, 1e-3) << "the glass moves the microimages at 450 nm";
    // The blue camera's own truth of the lenses it shares with the d line's list agrees.
    const std::vector<MicroimageTruth> own = microimage_truth(blue, default_microimage_options());
    int matched = 0;
    for (const MicroimageTruth& o : own)
        for (const MicroimageTruth& t : e)
            if (o.lens.k == t.lens.k && o.lens.l == t.lens.l && o.lit && t.lit) {
                EXPECT_NEAR(o.u_px, t.u_px, 1e-6);
                EXPECT_NEAR(o.v_px, t.v_px, 1e-6);
                ++matched;
            }
    EXPECT_GT(matched, 4);
}

TEST(MicroimageTruth, NothingWithoutAnArrayOrAMainLens)
{
    const PlenopticCamera no_array = with_film(make_camera(test::thin_lens_camera(50, 4, 52)), 100, 100);
    EXPECT_TRUE(microimage_truth(no_array, default_microimage_options()).empty());
    CameraParams p = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52);
    p.main.given = false;
    p.main.type = MainLensType::None;
    const PlenopticCamera no_main = with_film(make_camera(p), 100, 100);
    EXPECT_TRUE(microimage_truth(no_main, default_microimage_options()).empty());
}

} // namespace
} // namespace plenoptic
