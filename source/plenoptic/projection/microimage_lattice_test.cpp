// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of the microimage lattice and its LFToolbox form.

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::dir_of;
using test::origin_of;
using test::plenoptic_camera;
using test::str;
using test::thin_lens_camera;

// ---------------------------------------------------------------- microimage lattice

void check_lftoolbox(GridType grid, double rotate_z, double offset_x, double tx)
{
    CameraParams params = plenoptic_camera(grid, 0.137, 0.7, 0.7, 50, 5, 52);
    test::set_pose(&params, 0, 0, rotate_z, tx, -0.011, 0);
    params.sensor.offset_mm[0] = offset_x;
    ASSERT_EQ(check_camera(params), "");
    const PlenopticCamera m = make_camera(params);
    const int W = 320, H = 240;
    const MicroimageLattice lattice = microimage_lattice(with_film(m, W, H));
    ASSERT_TRUE(lattice.valid);
    ASSERT_TRUE(lattice.lftoolbox_valid);
    EXPECT_TRUE(lattice.exact);
    // The optics -> pixel map mirrors x, so a rotation theta appears as -theta.
    EXPECT_NEAR(lattice.rot, -rotate_z * kPi / 180, 1e-9) << "rotate " << rotate_z;
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
            const OwnLens lens_lookup = own_lens(m, with_film(m, W, H).sensor.point(u + 0.5, v + 0.5));
            ASSERT_TRUE(lens_lookup.found);
            const LensIndex lens = lens_lookup.lens;
            double cu, cv;
            const MicroimageCentre centre_cu = microimage_centre_px(with_film(m, W, H), lens);
            ASSERT_TRUE(centre_cu.valid);
            cu = centre_cu.u;
            cv = centre_cu.v;
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
    const MicroimageCentre centre_u0 = microimage_centre_px(with_film(m, W, H), from_skew(grid, 3, -2));
    ASSERT_TRUE(centre_u0.valid);
    u0 = centre_u0.u;
    v0 = centre_u0.v;
    const MicroimageCentre centre_u1 = microimage_centre_px(with_film(m, W, H), from_skew(grid, 4, -1));
    ASSERT_TRUE(centre_u1.valid);
    u1 = centre_u1.u;
    v1 = centre_u1.v;
    EXPECT_NEAR(u1 - u0, lattice.basis_a_px[0] + lattice.basis_b_px[0], 1e-6);
    EXPECT_NEAR(v1 - v0, lattice.basis_a_px[1] + lattice.basis_b_px[1], 1e-6);

    if (rotate_z == 0) {
        // Unrotated, every microimage centre in the image (up to LFToolbox's last pixel centre,
        // W and H 1-based) is on the grid: count them directly.
        int expected = 0;
        for (int l = -200; l <= 200; ++l) {
            for (int k = -200; k <= 200; ++k) {
                const MicroimageCentre c = microimage_centre_px(with_film(m, W, H), LensIndex{k, l});
                const double u = c.u, v = c.v;
                if (c.valid && u >= -0.5 && u <= W - 1 && v >= -0.5 && v <= H - 1)
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
    const PlenopticCamera m = with_film(make_camera(params), 320, 240);
    const MicroimageLattice lattice = microimage_lattice(m);
    ASSERT_TRUE(lattice.valid);
    EXPECT_FALSE(lattice.exact);
    // Still a tenth of a pixel near the centre.
    double u0, v0, u1, v1;
    const MicroimageCentre centre_u0 = microimage_centre_px(m, LensIndex{0, 0});
    ASSERT_TRUE(centre_u0.valid);
    u0 = centre_u0.u;
    v0 = centre_u0.v;
    const MicroimageCentre centre_u1 = microimage_centre_px(m, LensIndex{1, 0});
    ASSERT_TRUE(centre_u1.valid);
    u1 = centre_u1.u;
    v1 = centre_u1.v;
    EXPECT_NEAR(u1 - u0, lattice.basis_a_px[0], 0.1);
    EXPECT_NEAR(v1 - v0, lattice.basis_a_px[1], 0.1);
}

TEST(Optics, MicroimageCentreIsTheCentralProjectionOfTheLensCentre)
{
    // The chief ray from a microimage centre through its pinhole lens passes through the main-lens
    // centre.
    CameraParams params = plenoptic_camera(GridType::Hexagonal, 0.3, 0, 2, 50, 4, 52);
    test::set_pose(&params, 2, -1, 7, 0.02, 0.01, -0.1);
    const PlenopticCamera m = make_camera(params);
    const int W = 300, H = 300;
    for (int k = -4; k <= 4; ++k) {
        const LensIndex lens{k, k / 2};
        double u, v;
        const MicroimageCentre centre_u = microimage_centre_px(with_film(m, W, H), lens);
        ASSERT_TRUE(centre_u.valid);
        u = centre_u.u;
        v = centre_u.v;
        OpticsRay ray;
        ASSERT_TRUE((ray = chief_ray_through(with_film(m, W, H), u + 0.5, v + 0.5, &lens)).passed);
        EXPECT_LT(length(origin_of(ray)), 1e-9) << "lens " << k << " origin " << str(origin_of(ray));
    }
}

} // namespace
} // namespace plenoptic
