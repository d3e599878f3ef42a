// SPDX-License-Identifier: AGPL-3.0-or-later
// Samples where light passes (camera/aim.h): the regions the samples are aimed at hold every
// sensor point and cell point through which the renderer's own ray passes (brute force over
// sensor points and cell points, through ideal and traced main lenses, plenoptic 1.0 and 2.0
// arrays), the aimed samples give a pixel the same light as uniform ones (their weighted mean
// against a fine uniform count), and the aiming is off where it must be.

#include <cmath>

#include <gtest/gtest.h>

#include "plenoptic/camera/aim.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/core/sampling.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;
using test::vignetting_triplet;

struct AimCase {
    const char* name;
    CameraParams params;
};

CameraParams with_pixels(CameraParams p, double pixel_mm)
{
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = pixel_mm;
    return p;
}

// The vignetting triplet (traced, with pupil bounds; or its thick_lens equivalent) 55 mm in front
// of a hexagonal array of 0.3 mm thin lenses (f = 1.5 mm), the sensor d behind it.
CameraParams triplet_camera(bool thick, double d, GridType grid)
{
    CameraParams p = plenoptic_camera(grid, 0.3, 1.5, d, 50, 4, 55);
    p.main = MainLensParams();
    p.main.given = true;
    p.main.type = thick ? MainLensType::ThickLens : MainLensType::Prescription;
    p.main.has_prescription = true;
    p.main.prescription = vignetting_triplet();
    p.main.has_distance = true;
    p.main.distance_mm = 55;
    return with_pixels(p, 0.02);
}

// A camera whose lenses are displaced in the plane and along the axis and whose focal lengths
// scatter (the array's errors).
CameraParams with_errors(CameraParams p, double position_mm, double position_z_mm, double focal)
{
    p.array.has_errors = true;
    p.array.errors.position_sd_mm = position_mm;
    p.array.errors.position_sd_z_mm = position_z_mm;
    p.array.errors.focal_sd = focal;
    p.array.errors.seed = 7;
    return p;
}

std::vector<AimCase> setups()
{
    return {
        {"thin lens, plenoptic 1.0, hexagonal", with_pixels(plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52), 0.05)},
        {"thin lens, plenoptic 2.0, hexagonal", with_pixels(plenoptic_camera(GridType::Hexagonal, 0.5, 2, 1.5, 50, 4, 52), 0.05)},
        {"thin lens, plenoptic 2.0 (d > f), square", with_pixels(plenoptic_camera(GridType::Rectangular, 0.5, 2, 2.6, 50, 4, 52), 0.05)},
        {"thick lens, plenoptic 1.0", triplet_camera(true, 1.5, GridType::Hexagonal)},
        {"traced triplet, plenoptic 1.0", triplet_camera(false, 1.5, GridType::Hexagonal)},
        {"traced triplet, plenoptic 2.0", triplet_camera(false, 1.1, GridType::Hexagonal)},
        {"traced triplet, plenoptic 2.0, square", triplet_camera(false, 1.9, GridType::Rectangular)},
        {"thin lens, plenoptic 1.0, lenses displaced and their focal lengths scattered",
         with_errors(with_pixels(plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52), 0.05), 0.01, 0.02, 0.03)},
        {"traced triplet, plenoptic 2.0, lenses displaced in the plane and their focal lengths scattered",
         with_errors(triplet_camera(false, 1.1, GridType::Hexagonal), 0.01, 0, 0.03)},
    };
}

TEST(Aim, CellHalfHeightIsTheLatticeCell)
{
    for (GridType grid : {GridType::Hexagonal, GridType::Rectangular}) {
        const double pitch = 0.7;
        int checked = 0;
        for (int b = 0; b <= 200; ++b)
            for (int a = 0; a <= 200; ++a) {
                const double x = -0.6 * pitch + 1.2 * pitch * a / 200, y = -0.7 * pitch + 1.4 * pitch * b / 200;
                const double half = cell_half_height(grid, pitch, x);
                const bool in_cell = nearest_lens(grid, pitch, x, y) == LensIndex{0, 0};
                const bool inside = std::fabs(y) <= half;
                // Points within a rounding distance of the boundary may go either way.
                const double margin = std::fabs(std::fabs(y) - half);
                if (margin > 1e-9 && std::fabs(std::fabs(x) - 0.5 * pitch) > 1e-9) {
                    EXPECT_EQ(in_cell, inside) << x << " " << y;
                    ++checked;
                }
            }
        EXPECT_GT(checked, 30000);
        // And every uniform cell sample lies within it.
        for (int n = 0; n < 4096; ++n) {
            const CameraSample s = make_sample(3, 5, n, 4096);
            const Vec2 h = sample_cell_uniform(grid, pitch, s.lens_u, s.lens_v);
            EXPECT_LE(std::fabs(h.y), cell_half_height(grid, pitch, h.x) + 1e-12);
        }
    }
}

// Every (sensor point, cell point) pair through which the renderer's unaimed ray passes, for the
// sensor points of a grid over the picture and the cell points of a grid over the cell, through
// the point's own lens and its neighbours: the sensor point lies in the lens's lit_sensor_disc and
// the cell point in lit_cell_disc of the sensor point, and behind the traced lens in both cuts'
// (lit_sensor_cut, lit_cell_cut).
TEST(Aim, DiscsHoldEveryPassingRay)
{
    for (const AimCase& setup : setups()) {
        const int W = 160, H = 120;
        const PlenopticCamera m = with_film(make_camera(setup.params), W, H);
        ASSERT_TRUE(m.sampling.aim) << setup.name;
        long passing = 0, sensor_out = 0, cell_out = 0, aimed_lenses = 0, cut_lenses = 0;
        const int cells = 20;
        for (int b = 0; b <= 30; ++b) {
            for (int a = 0; a <= 40; ++a) {
                // Across the whole picture, off the pixel grid's symmetry.
                const double pu = (a + 0.37) * W / 40.0, pv = (b + 0.61) * H / 30.0;
                const Vec3 p = m.sensor.point(pu, pv);
                const OwnLens own = own_lens(m, p);
                if (!own.found)
                    continue;
                const LensIndex lenses[3] = {own.lens, LensIndex{own.lens.k + 1, own.lens.l},
                                             LensIndex{own.lens.k, own.lens.l + 1}};
                for (const LensIndex& lens : lenses) {
                    LensAim aim;
                    if (!lens_aim(m, lens, &aim))
                        continue;
                    ++aimed_lenses;
                    const Vec3 s = m.array.to_local(p);
                    const AimDisc sensor = lit_sensor_disc(aim, aim.z - s.z);
                    const AimDisc cell = lit_cell_disc(aim, s);
                    AimDisc sensor_cuts[2], cell_cuts[2];
                    for (int k = 0; k < aim.cuts; ++k) {
                        sensor_cuts[k] = lit_sensor_cut(aim, aim.z - s.z, k);
                        cell_cuts[k] = lit_cell_cut(aim, s, k);
                    }
                    cut_lenses += aim.cuts > 0 ? 1 : 0;
                    for (int j = 0; j < cells; ++j) {
                        for (int i = 0; i < cells; ++i) {
                            const double u = (i + 0.5) / cells, v = (j + 0.5) / cells;
                            const OpticsRay ray = generate_ray_unaimed(m, 0, 0, CameraSample{pu, pv, u, v}, &lens);
                            if (!ray.passed)
                                continue;
                            ++passing;
                            if (std::hypot(s.x - sensor.centre.x, s.y - sensor.centre.y) > sensor.radius)
                                ++sensor_out;
                            const Vec2 h = m.array.cell_point(u, v);
                            if (std::hypot(h.x - cell.centre.x, h.y - cell.centre.y) > cell.radius)
                                ++cell_out;
                            for (int k = 0; k < aim.cuts; ++k) {
                                const AimDisc& a = sensor_cuts[k];
                                const AimDisc& b = cell_cuts[k];
                                if (std::hypot(s.x - a.centre.x, s.y - a.centre.y) > a.radius)
                                    ++sensor_out;
                                if (std::hypot(h.x - b.centre.x, h.y - b.centre.y) > b.radius)
                                    ++cell_out;
                            }
                        }
                    }
                }
            }
        }
        EXPECT_GT(passing, 20000) << setup.name;
        EXPECT_GT(aimed_lenses, 1000) << setup.name;
        EXPECT_EQ(sensor_out, 0) << setup.name;
        EXPECT_EQ(cell_out, 0) << setup.name;
        // Behind the traced triplet most lenses are off the axis: cut as well.
        if (setup.params.main.type == MainLensType::Prescription)
            EXPECT_GT(cut_lenses, 500) << setup.name;
        else
            EXPECT_EQ(cut_lenses, 0) << setup.name;
    }
}

// The aimed samples of a pixel, weighted, give the light uniform samples give: for pixels across a
// microimage's rim and in its middle, the weighted pass count of 2048 aimed samples against the
// pass fraction of 8192 uniform ones; and aimed samples pass at least as often.
TEST(Aim, AimedSamplesGiveThePixelTheSameLight)
{
    for (const AimCase& setup : setups()) {
        const int W = 160, H = 120;
        const PlenopticCamera m = with_film(make_camera(setup.params), W, H);
        int compared = 0, gained = 0;
        for (int j = 50; j < 70; j += 4) {
            for (int i = 70; i < 90; i += 4) {
                double uniform = 0, aimed = 0;
                long uniform_passed = 0, aimed_passed = 0;
                const int n_uniform = 8192, n_aimed = 2048;
                for (int n = 0; n < n_uniform; ++n) {
                    const OpticsRay ray = generate_ray_unaimed(m, i, j, make_sample(i, j, n, n_uniform));
                    if (ray.passed) {
                        uniform += ray.weight;
                        ++uniform_passed;
                    }
                }
                for (int n = 0; n < n_aimed; ++n) {
                    const OpticsRay ray = generate_ray(m, i, j, make_sample(i, j, n, n_aimed));
                    if (ray.passed) {
                        aimed += ray.weight;
                        ++aimed_passed;
                    }
                }
                uniform /= n_uniform;
                aimed /= n_aimed;
                if (uniform == 0) {
                    EXPECT_EQ(aimed, 0) << setup.name << " pixel " << i << ", " << j;
                    continue;
                }
                ++compared;
                EXPECT_NEAR(aimed, uniform, 0.01 + 0.02 * uniform) << setup.name << " pixel " << i << ", " << j;
                EXPECT_GE(double(aimed_passed) / n_aimed, double(uniform_passed) / n_uniform - 0.01)
                    << setup.name << " pixel " << i << ", " << j;
                if (double(aimed_passed) / n_aimed > double(uniform_passed) / n_uniform + 0.05)
                    ++gained;
            }
        }
        EXPECT_GT(compared, 10) << setup.name;
        EXPECT_GT(gained, 0) << setup.name;  // some pixel's samples pass markedly more often
    }
}

// A pixel in the middle of a plenoptic 1.0 microimage through a thin main lens: the whole pixel and
// the whole cell are lit, so its aimed rays are the uniform rays, bit for bit.
TEST(Aim, WhollyLitPixelKeepsItsUniformRays)
{
    const PlenopticCamera m = with_film(make_camera(setups()[0].params), 160, 120);
    ASSERT_TRUE(m.sampling.aim);
    const int i = 80, j = 60;  // on the axis: the middle of the central microimage
    for (int n = 0; n < 64; ++n) {
        const CameraSample s = make_sample(i, j, n, 64);
        const OpticsRay a = generate_ray(m, i, j, s), b = generate_ray_unaimed(m, i, j, s);
        ASSERT_EQ(a.passed, b.passed);
        EXPECT_EQ(a.weight, b.weight);
        EXPECT_EQ(a.dir.x, b.dir.x);
        EXPECT_EQ(a.dir.y, b.dir.y);
        EXPECT_EQ(a.origin_mm.x, b.origin_mm.x);
    }
}

TEST(Aim, OffWhereItCannotAim)
{
    const CameraParams thin = plenoptic_camera(GridType::Hexagonal, 0.5, 2, 2, 50, 4, 52);
    EXPECT_TRUE(make_camera(thin).sampling.aim);
    CameraParams one = thin;
    one.sampling.samples = 1;
    EXPECT_FALSE(make_camera(one).sampling.aim);  // the chief ray alone
    EXPECT_FALSE(make_camera(plenoptic_camera(GridType::Hexagonal, 0.5, 0, 2, 50, 4, 52)).sampling.aim);  // pinholes
    CameraParams tilted = thin;
    test::set_pose(&tilted, 1, 0, 0, 0, 0, 0);
    EXPECT_FALSE(make_camera(tilted).sampling.aim);
    CameraParams turned = thin;
    test::set_pose(&turned, 0, 0, 30, 0, 0, 0);  // turned in its plane only: still parallel
    EXPECT_TRUE(make_camera(turned).sampling.aim);
    CameraParams tilting = thin;
    tilting.array.has_errors = true;
    tilting.array.errors.rotation_deg = 1;  // lenses tilted by their errors
    EXPECT_FALSE(make_camera(tilting).sampling.aim);
    CameraParams gapped = thin;
    gapped.array.fill_factor = 0.8;  // light through the gap is not bent
    EXPECT_FALSE(make_camera(gapped).sampling.aim);
    CameraParams bare = thin;
    bare.main = MainLensParams();
    EXPECT_FALSE(make_camera(bare).sampling.aim);  // no main lens
    EXPECT_FALSE(make_camera(test::thin_lens_camera(50, 4, 52)).sampling.aim);  // no array
}

} // namespace
} // namespace plenoptic
