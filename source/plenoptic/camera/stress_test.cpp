// SPDX-License-Identifier: AGPL-3.0-or-later
// Stress tests: singular-looking and extreme parameters give finite unit directions, never NaN.

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/truth/metadata.h"
#include "plenoptic/camera/pixel.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {

using test::plenoptic_camera;
using test::str;

struct StressCase {
    std::string name;
    CameraParams params;
};

std::vector<StressCase> stress_cases()
{
    std::vector<StressCase> cases;
    const double f = 2.0;
    cases.push_back({"d = f exactly", plenoptic_camera(GridType::Hexagonal, 0.3, f, f, 50, 4, 52)});
    cases.push_back({"d = f (1 + 1e-12)", plenoptic_camera(GridType::Hexagonal, 0.3, f, f * (1 + 1e-12), 50, 4, 52)});
    cases.push_back({"d = f (1 - 1e-12)", plenoptic_camera(GridType::Rectangular, 0.3, f, f * (1 - 1e-12), 50, 4, 52)});
    cases.push_back({"D = F exactly", plenoptic_camera(GridType::Hexagonal, 0.3, f, f, 50, 4, 50)});
    cases.push_back({"D = F, no array", test::thin_lens_camera(50, 4, 50)});
    cases.push_back({"microlens f 1e-6", plenoptic_camera(GridType::Hexagonal, 0.3, 1e-6, 2, 50, 4, 52)});
    cases.push_back({"microlens f 1e6", plenoptic_camera(GridType::Hexagonal, 0.3, 1e6, 2, 50, 4, 52)});
    cases.push_back({"main F 1e-6", plenoptic_camera(GridType::Hexagonal, 0.3, f, 2, 1e-6, 4, 52)});
    cases.push_back({"main F 1e6", plenoptic_camera(GridType::Hexagonal, 0.3, f, 2, 1e6, 4, 52)});
    cases.push_back({"main F 1e6, no array", test::thin_lens_camera(1e6, 4, 52)});
    cases.push_back({"main F 1e-6, no array", test::thin_lens_camera(1e-6, 4, 52)});
    CameraParams focus_far = plenoptic_camera(GridType::Hexagonal, 0.3, f, f, 50, 4, 0);
    focus_far.main.has_distance = false;
    focus_far.main.has_focus_distance = true;
    focus_far.main.focus_distance_units = 1e300;
    cases.push_back({"focus at 1e300 units", focus_far});
    CameraParams pinhole_main;
    pinhole_main.main.given = true;
    pinhole_main.main.type = MainLensType::Pinhole;
    pinhole_main.main.has_distance = true;
    pinhole_main.main.distance_mm = 52;
    test::add_array(&pinhole_main, GridType::Hexagonal, 0.3, 1.0 / (1.0 / 52 + 1.0 / 2) * (1 + 1e-9), 2);
    cases.push_back({"pinhole main, nearly degenerate microlens", pinhole_main});

    for (double angle : {0.0, 1e-9, 45.0, 89.99}) {
        for (int axis = 0; axis < 3; ++axis) {
            for (int variant = 0; variant < 3; ++variant) {
                CameraParams p = variant == 0   ? plenoptic_camera(GridType::Hexagonal, 0.3, f, 2.5, 50, 4, 52)
                                 : variant == 1 ? plenoptic_camera(GridType::Rectangular, 0.3, 0, 2.5, 50, 4, 52)
                                                : CameraParams();
                if (variant == 2)
                    test::add_array(&p, GridType::Hexagonal, 0.3, f, 2.5);
                if (variant == 1 && axis == 0) {
                    p.main = pinhole_main.main;  // pinhole main lens with a thin array
                    p.array.lens = MicrolensType::ThinLens;
                    p.array.focal_length_count = 1;
                    p.array.focal_lengths_mm[0] = f;
                }
                p.array.rotate_deg[axis] = angle;
                const char* variants[3] = {"thin+thin", "thin+pinholes", "no main lens"};
                cases.push_back({std::string(variants[variant]) + " rotate axis " + std::to_string(axis) + " by " +
                                     format_number(angle),
                                 p});
            }
        }
    }
    return cases;
}

void expect_unit_and_finite(const OpticsRay& ray, const std::string& what)
{
    const Vec3 o = test::origin_of(ray), d = test::dir_of(ray);
    ASSERT_TRUE(is_finite(o)) << what << " origin " << str(o);
    ASSERT_TRUE(is_finite(d)) << what << " direction " << str(d);
    ASSERT_NEAR(length(d), 1.0, 1e-12) << what << " direction " << str(d);
    ASSERT_GT(d.z, 0.0) << what << " direction " << str(d) << " must point into the scene";
}

TEST(Stress, ExtremeParametersGiveFiniteUnitDirections)
{
    const int W = 24, H = 18;
    for (StressCase& c : stress_cases()) {
        c.params.sampling.samples = 4;
        ASSERT_EQ(check_camera(c.params), "") << c.name;
        const PlenopticCamera m = with_film(make_camera(c.params), W, H);
        int unblocked = 0;
        for (int j = 0; j < H; ++j) {
            for (int i = 0; i < W; ++i) {
                for (int n = 0; n < 4; ++n) {
                    OpticsRay ray;
                    if ((ray = m.generate_ray(i, j, make_sample(i, j, n, 4))).passed) {
                        ++unblocked;
                        expect_unit_and_finite(ray, c.name + " generate_ray");
                    }
                }
                expect_unit_and_finite(m.chief_ray(i, j), c.name + " chief_ray");
                const Rgbt value = shade_pixel(m, i, j, [](const OpticsRay& r) {
                    return Rgbt{r.dir.x, r.dir.y, r.dir.z, 0};
                });
                ASSERT_TRUE(std::isfinite(value.r) && std::isfinite(value.g) && std::isfinite(value.b) &&
                            std::isfinite(value.t))
                    << c.name << " pixel " << i << "," << j;
            }
        }
        RecordProperty(c.name, unblocked);
        for (double z : {1.0, 60.0, 1e4, 1e9}) {
            const Vec3 point{0.01 * z, -0.02 * z, z};
            for (const PixelHit& hit : m.project(point))
                ASSERT_TRUE(std::isfinite(hit.u) && std::isfinite(hit.v)) << c.name << " z " << z;
        }
        CameraFrame frame = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        const std::string json = metadata_json(m, c.params, frame, "");
        EXPECT_EQ(json.find("nan"), std::string::npos) << c.name;
        EXPECT_EQ(json.find("inf"), std::string::npos) << c.name;
    }
}

TEST(Stress, HugeCoordinatesDoNotOverflowTheLattice)
{
    // The smallest lengths allowed (1e-12 mm) under a 10 um pixel: 1e20 lenses per pixel.
    CameraParams p = plenoptic_camera(GridType::Hexagonal, kMinLengthMm, kMinLengthMm, kMinLengthMm, 50, 4, 52);
    ASSERT_EQ(check_camera(p), "");
    EXPECT_NE(check_camera(plenoptic_camera(GridType::Hexagonal, 1e-200, 1e-200, 1e-200, 50, 4, 52)), "")
        << "lengths below 1 nm leave double precision in products: refused";
    const PlenopticCamera m = with_film(make_camera(p), 8, 8);
    for (int n = 0; n < 16; ++n) {
        OpticsRay ray;
        if ((ray = m.generate_ray(0, 0, make_sample(0, 0, n, 16))).passed)
            expect_unit_and_finite(ray, "tiny pitch");
    }
    const Vec3 point{1, 2, 1000};
    EXPECT_TRUE(m.project(point).size() <= 1u);
    const MicroimageLattice lattice = microimage_lattice(m);
    if (lattice.lftoolbox_valid) {
        for (double x : {lattice.h_spacing, lattice.v_spacing, lattice.h_offset, lattice.v_offset, lattice.rot})
            EXPECT_TRUE(std::isfinite(x)) << "LFToolbox fields of a 1 nm pitch array";
    }
}

} // namespace
} // namespace plenoptic
