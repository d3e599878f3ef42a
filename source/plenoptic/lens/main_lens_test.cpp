// SPDX-License-Identifier: AGPL-3.0-or-later
// One main-lens interface. The thin lens keeps its formulas; a prescription's exact trace
// and its paraxial (thick-lens) equivalent agree for paraxial rays, and the thick lens images a
// point where the thick-lens formulas say.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "plenoptic/core/json.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/main_lens_params.h"
#include "plenoptic/lens/prescription.h"

namespace plenoptic {
namespace {

// A biconvex singlet (R1 = 100, R2 = -100, n = 1.5, t = 8) 10 mm behind a stop.
Prescription singlet()
{
    Prescription lens;
    lens.surfaces.push_back(LensSurface{0, 10, 0, 10, true, 1});
    lens.surfaces.push_back(LensSurface{100, 8, 1.5, 40, false, 2});
    lens.surfaces.push_back(LensSurface{-100, 0, 1, 40, false, 3});
    return lens;
}

TEST(MainLens, ThinLensRefractsByItsFocalLength)
{
    MainLensParams p;
    p.given = true;
    p.type = MainLensType::ThinLens;
    p.focal_length_mm = 50;
    p.has_f_number = true;
    p.f_number = 2;
    const std::shared_ptr<const MainLens> lens = make_main_lens(p, 100);
    ASSERT_TRUE(lens);
    EXPECT_DOUBLE_EQ(lens->exit_pupil_radius(), 12.5);
    // A ray from the axial point 100 mm behind a 50 mm lens leaves parallel (1/50 = 1/100 + 1/100
    // images it at 100 mm in front: the ray through (5, 0) heads to (0, 0, 100)).
    const SceneRay out = lens->to_scene(Vec3{0, 0, -100}, Vec3{5, 0, 100}, true);
    ASSERT_TRUE(out.passed);
    EXPECT_NEAR(out.dir.x / out.dir.z, -5.0 / 100, 1e-15);
    EXPECT_FALSE(lens->to_scene(Vec3{0, 0, -100}, Vec3{13, 0, 100}, true).passed);  // outside the aperture
    EXPECT_TRUE(lens->to_scene(Vec3{0, 0, -100}, Vec3{13, 0, 100}, false).passed);
}

TEST(MainLens, ExactTraceAndThickEquivalentAgreeForParaxialRays)
{
    const std::shared_ptr<const MainLens> exact = make_prescription_lens(singlet(), 0, true);
    const std::shared_ptr<const MainLens> thick = make_prescription_lens(singlet(), 0, false);
    ASSERT_TRUE(exact && thick);
    // Rays from a sensor point 120 mm behind the rear vertex through points near the axis.
    for (double h : {0.001, 0.01, 0.05}) {
        const Vec3 from{0.02, -0.01, -120};
        const Vec3 towards{h, 0.5 * h, 0};
        const SceneRay a = exact->to_scene(from, towards - from, true);
        const SceneRay b = thick->to_scene(from, towards - from, true);
        ASSERT_TRUE(a.passed && b.passed) << h;
        // Same direction and same line (compare where each crosses the plane z = 100).
        EXPECT_NEAR(a.dir.x / a.dir.z, b.dir.x / b.dir.z, 1e-5 * (h + 1e-3)) << h;
        EXPECT_NEAR(a.dir.y / a.dir.z, b.dir.y / b.dir.z, 1e-5 * (h + 1e-3)) << h;
        const double ta = (100 - a.origin.z) / a.dir.z, tb = (100 - b.origin.z) / b.dir.z;
        EXPECT_NEAR(a.origin.x + ta * a.dir.x, b.origin.x + tb * b.dir.x, 1e-3) << h;
        EXPECT_NEAR(a.origin.y + ta * a.dir.y, b.origin.y + tb * b.dir.y, 1e-3) << h;
    }
}

TEST(MainLens, ThickLensImagesAPointAtTheThickLensConjugate)
{
    // The thick lens's image of an axial point must be where the exact trace focuses paraxial rays
    // from it; and where the paraxial image distance of the prescription puts it.
    const Prescription lens = singlet();
    const std::shared_ptr<const MainLens> thick = make_prescription_lens(lens, 0, false);
    const double length = 18;  // rear vertex at optics z = 0, front vertex at 18
    const double object_mm = 1000;  // in front of the front vertex
    const HomogeneousPoint image = thick->paraxial_image(Vec3{0, 0, length + object_mm});
    ASSERT_NE(image.w, 0);
    const double image_z = image.xyz.z / image.w;
    const ImageDistance d = paraxial_image_distance(lens, object_mm);
    ASSERT_TRUE(d.real);
    EXPECT_NEAR(-image_z, d.mm, 1e-9 * d.mm);
    // A paraxial ray from the image point back through the exact lens heads for the object point.
    const std::shared_ptr<const MainLens> exact = make_prescription_lens(lens, 0, true);
    const SceneRay out = exact->to_scene(Vec3{0, 0, image_z}, Vec3{1e-3, 0, -image_z}, true);
    ASSERT_TRUE(out.passed);
    const double t = (length + object_mm - out.origin.z) / out.dir.z;
    EXPECT_NEAR(out.origin.x + t * out.dir.x, 0, 1e-3);
}

TEST(MainLens, ExactLensBlocksAtTheStopAndAtTheRims)
{
    const std::shared_ptr<const MainLens> exact = make_prescription_lens(singlet(), 0, true);
    // Parallel rays from behind (image side) at growing heights: the 10 mm stop in front passes
    // only those that reach it within 5 mm.
    int passed = 0;
    for (double h = 0.25; h < 20; h += 0.5)
        passed += exact->to_scene(Vec3{h, 0, -50}, Vec3{0, 0, 1}, true).passed;
    EXPECT_GT(passed, 0);
    EXPECT_LT(passed, 20);
    // Without apertures (chief rays, depth maps) they all pass.
    for (double h = 0.25; h < 19; h += 0.5)
        EXPECT_TRUE(exact->to_scene(Vec3{h, 0, -50}, Vec3{0, 0, 1}, false).passed) << h;
}

// Optical reversibility: light sent back along the ray that to_scene returns leaves the lens,
// through to_image, along the ray it came from (the same line, travelling the other way); a ray
// For every kind of lens with an aperture.
TEST(MainLens, ToImageRetracesToScene)
{
    MainLensParams thin;
    thin.given = true;
    thin.type = MainLensType::ThinLens;
    thin.focal_length_mm = 50;
    thin.has_f_number = true;
    thin.f_number = 2;
    std::vector<std::shared_ptr<const MainLens>> lenses;
    lenses.push_back(make_main_lens(thin, 100));
    lenses.push_back(make_prescription_lens(singlet(), 0, false));
    lenses.push_back(make_prescription_lens(singlet(), 0, true));
    for (size_t which = 0; which < lenses.size(); ++which) {
        const MainLens& lens = *lenses[which];
        int passed = 0, blocked = 0;
        for (int i = -6; i <= 6; ++i) {
            for (int j = -6; j <= 6; ++j) {
                const Vec3 origin{0.3 * i, -0.2 * j, -60};
                const Vec3 aim = lens.exit_pupil_centre() + Vec3{2.5 * i, 1.9 * j, 0};
                const SceneRay out = lens.to_scene(origin, aim - origin, true);
                const ImageRay back = lens.to_image(out.origin + 30.0 * out.dir, -out.dir, true);
                if (!out.passed) {
                    ++blocked;
                    continue;
                }
                ++passed;
                ASSERT_TRUE(back.passed) << "lens " << which << " ray " << i << ", " << j;
                // The returning ray lies on the original line and travels back along it.
                const Vec3 d = normalized(aim - origin);
                const Vec3 rel = back.origin - origin;
                EXPECT_LT(length(cross(rel, d)), 1e-9) << "lens " << which << " ray " << i << ", " << j;
                EXPECT_LT(length(back.dir + d), 1e-12) << "lens " << which << " ray " << i << ", " << j;
            }
        }
        EXPECT_GT(passed, 20) << "lens " << which;
        EXPECT_GT(blocked, 10) << "lens " << which << ": its aperture blocks some of these rays";
    }
}

// The main_lens section (docs/metadata.md): the members every lens writes, in order, then the
// kind's own; D, the focus distance and the lens file come from where the camera holds the lens.
std::vector<std::string> keys(const MetadataJson& section)
{
    std::vector<std::string> out;
    for (auto it = section.begin(); it != section.end(); ++it)
        out.push_back(it.key());
    return out;
}

TEST(MainLens, EachKindWritesItsMetadataSection)
{
    const std::vector<std::string> common = {"type", "focal_length_mm", "aperture_mm", "f_number", "distance_mm",
                                             "focus_distance"};
    const LensPlacement at_30{30, false, 0, ""};

    const MetadataJson none = main_lens_metadata(nullptr, at_30);
    EXPECT_EQ(keys(none), common);
    EXPECT_EQ(none["type"], "none");
    EXPECT_TRUE(none["distance_mm"].is_null());

    const MetadataJson pinhole = main_lens_metadata(make_pinhole_lens().get(), at_30);
    EXPECT_EQ(keys(pinhole), common);
    EXPECT_EQ(pinhole["type"], "pinhole");
    EXPECT_TRUE(pinhole["focal_length_mm"].is_null() && pinhole["aperture_mm"].is_null() && pinhole["f_number"].is_null());
    EXPECT_EQ(pinhole["distance_mm"], 30);

    const MetadataJson thin = main_lens_metadata(make_thin_lens(25, 5, 5, nullptr, -30).get(), LensPlacement{30, true, 2.5, ""});
    EXPECT_EQ(keys(thin), common);
    EXPECT_EQ(thin["focal_length_mm"], 25);
    EXPECT_EQ(thin["f_number"], 5);
    EXPECT_EQ(thin["focus_distance"], 2.5);

    const DistortionParams distortion{{-0.1, 0.02, 0}, {0.001, 0}};
    const MetadataJson distorted = main_lens_metadata(make_thin_lens(25, 5, 5, &distortion, -30).get(), at_30);
    std::vector<std::string> with_distortion = common;
    with_distortion.push_back("distortion");
    EXPECT_EQ(keys(distorted), with_distortion);
    EXPECT_EQ(distorted["distortion"]["radial"], MetadataJson::parse("[-0.1, 0.02, 0]"));
    EXPECT_EQ(distorted["distortion"]["tangential"], MetadataJson::parse("[0.001, 0]"));
    EXPECT_EQ(distorted["distortion"]["plane_z_mm"], -30);

    // Both models of a prescription write its surfaces and first-order data; its length is the sum
    // of the thicknesses (10 + 8 + 0 mm).
    std::vector<std::string> with_prescription = common;
    with_prescription.push_back("prescription");
    with_prescription.push_back("paraxial");
    const LensPlacement held{120, false, 0, "singlet.dat"};
    const MetadataJson exact = main_lens_metadata(make_prescription_lens(singlet(), 0, true, 120).get(), held);
    const MetadataJson thick = main_lens_metadata(make_prescription_lens(singlet(), 0, false, 120).get(), held);
    EXPECT_EQ(keys(exact), with_prescription);
    EXPECT_EQ(exact["type"], "prescription");
    EXPECT_EQ(thick["type"], "thick_lens");
    EXPECT_EQ(exact["prescription"], thick["prescription"]);
    EXPECT_EQ(exact["paraxial"], thick["paraxial"]);
    EXPECT_EQ(exact["prescription"]["lens_file"], "singlet.dat");
    ASSERT_EQ(exact["prescription"]["surfaces"].size(), 3u);
    EXPECT_EQ(exact["prescription"]["surfaces"][0]["stop"], true);
    EXPECT_EQ(exact["prescription"]["surfaces"][1]["radius_mm"], 100);
    EXPECT_EQ(exact["paraxial"]["length_mm"], 18);
    EXPECT_EQ(exact["paraxial"]["front_vertex_z_mm"], 18);
}

} // namespace
} // namespace plenoptic
