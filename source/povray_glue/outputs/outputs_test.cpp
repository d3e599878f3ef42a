// SPDX-License-Identifier: AGPL-3.0-or-later
// The outputs as a list: which outputs a camera setup wants (against the rules of
// docs/specification.md, the keyword table and section 5), the drivers' order and their
// all-run / stop-at-refusal rules with test-only outputs, the depth map's per-pixel hook (and a
// continued render's backfill) through a made-up scene, and the hand-over keyed by the view.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ImfFrameBuffer.h>
#include <ImfInputFile.h>

#include "plenoptic/camera/pixel.h"
#include "plenoptic/core/test_util.h"
#include "povray_glue/outputs/output.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {
namespace {

using test::add_array;
using test::plenoptic_camera;
using test::thin_lens_camera;

std::shared_ptr<CameraSetup> setup_of(const CameraParams& params)
{
    std::shared_ptr<CameraSetup> setup = std::make_shared<CameraSetup>();
    setup->params = params;
    setup->model = make_camera(params);
    return setup;
}

CameraFrame test_frame()
{
    return CameraFrame{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
}

RenderArea whole(int W, int H) { return RenderArea{PixelRect{0, 0, W - 1, H - 1}, {}}; }

std::vector<std::string> wanted(const std::shared_ptr<CameraSetup>& setup)
{
    return Render(setup, test_frame(), 40, 30, whole(40, 30)).output_names();
}

typedef std::vector<std::string> Names;

// A plenoptic camera: thin main lens (50 mm, f/4) and a rectangular array of thin microlenses of
// focal length f, 0.5 mm behind which the sensor lies: f = 0.5 is plenoptic 1.0 (unfocused),
// f = 0.3 a focused (2.0) camera.
CameraParams plenoptic(double micro_focal_mm) { return plenoptic_camera(GridType::Rectangular, 0.1, micro_focal_mm, 0.5, 50, 4, 52); }

bool no_cancel() { return false; }

// ---- which outputs a setup wants ---------------------------------------------------------

TEST(OutputList, RunsDiffractionBeforeTheImageAndTheMetadataLast)
{
    const std::vector<OutputKind>& kinds = output_kinds();
    ASSERT_FALSE(kinds.empty());
    EXPECT_EQ(std::string("diffraction"), kinds.front().name);
    EXPECT_EQ(std::string("metadata"), kinds.back().name);
    // Each name once.
    for (size_t a = 0; a < kinds.size(); ++a)
        for (size_t b = a + 1; b < kinds.size(); ++b)
            EXPECT_NE(std::string(kinds[a].name), std::string(kinds[b].name));
}

TEST(WantedOutputs, ACameraWithNothingAskedWritesOnlyTheMetadata)
{
    EXPECT_EQ(Names({"metadata"}), wanted(setup_of(thin_lens_camera(50, 4, 52))));
    EXPECT_EQ(Names({"metadata"}), wanted(setup_of(plenoptic(0.5))));
}

TEST(WantedOutputs, DepthMapAndTheVirtualDepthOfAFocusedCamera)
{
    std::shared_ptr<CameraSetup> unfocused = setup_of(plenoptic(0.5));
    unfocused->depth_map = true;
    EXPECT_EQ(Names({"depth_map", "metadata"}), wanted(unfocused));

    std::shared_ptr<CameraSetup> focused = setup_of(plenoptic(0.3));
    EXPECT_EQ(Names({"metadata"}), wanted(focused));  // virtual depth only with the depth map
    focused->depth_map = true;
    EXPECT_EQ(Names({"depth_map", "virtual_depth", "metadata"}), wanted(focused));

    std::shared_ptr<CameraSetup> no_array = setup_of(thin_lens_camera(50, 4, 52));
    no_array->depth_map = true;
    EXPECT_EQ(Names({"depth_map", "metadata"}), wanted(no_array));
}

TEST(WantedOutputs, MicroimageCentresNeedAMainLensAndAnArray)
{
    // Default: only where the centres leave the lattice (a thin lens with distortion).
    std::shared_ptr<CameraSetup> plain = setup_of(plenoptic(0.5));
    EXPECT_EQ(Names({"metadata"}), wanted(plain));
    plain->microimage_centres = CameraSetup::kWrite;
    EXPECT_EQ(Names({"microimages", "metadata"}), wanted(plain));

    CameraParams distorted_params = plenoptic(0.5);
    distorted_params.main.has_distortion = true;
    distorted_params.main.distortion.radial[0] = 0.01;
    std::shared_ptr<CameraSetup> distorted = setup_of(distorted_params);
    EXPECT_EQ(Names({"microimages", "metadata"}), wanted(distorted));
    distorted->microimage_centres = CameraSetup::kDoNotWrite;
    EXPECT_EQ(Names({"metadata"}), wanted(distorted));

    // A camera array (no main lens) and a lens without an array: no effect.
    CameraParams array_only;
    add_array(&array_only, GridType::Rectangular, 0.1, 0.5, 0.5);
    std::shared_ptr<CameraSetup> bare = setup_of(array_only);
    bare->microimage_centres = CameraSetup::kWrite;
    EXPECT_EQ(Names({"metadata"}), wanted(bare));
    std::shared_ptr<CameraSetup> lens_only = setup_of(thin_lens_camera(50, 4, 52));
    lens_only->microimage_centres = CameraSetup::kWrite;
    EXPECT_EQ(Names({"metadata"}), wanted(lens_only));
}

TEST(WantedOutputs, RawWhiteImagesAndDiffraction)
{
    CameraParams params = plenoptic(0.5);
    params.sensor.chain.given = true;
    std::shared_ptr<CameraSetup> raw = setup_of(params);
    EXPECT_EQ(Names({"raw", "metadata"}), wanted(raw));
    raw->white_image.given = true;
    EXPECT_EQ(Names({"raw", "white_images", "metadata"}), wanted(raw));

    // Diffraction: the microlenses' Airy pattern (thin microlenses), or the main lens's without
    // an array; pinhole microlenses have none.
    CameraParams thin = plenoptic(0.5);
    thin.diffraction.given = true;
    EXPECT_EQ(Names({"diffraction", "metadata"}), wanted(setup_of(thin)));
    CameraParams lens = thin_lens_camera(50, 4, 52);
    lens.diffraction.given = true;
    EXPECT_EQ(Names({"diffraction", "metadata"}), wanted(setup_of(lens)));
    CameraParams pinholes = plenoptic_camera(GridType::Rectangular, 0.1, 0, 0.5, 50, 4, 52);
    pinholes.diffraction.given = true;
    EXPECT_EQ(Names({"metadata"}), wanted(setup_of(pinholes)));
}

// ---- the drivers, with test-only outputs ---------------------------------------------------

std::vector<std::string>& hook_log()
{
    static std::vector<std::string> log;
    return log;
}

// Records its hooks; "refuses" also refuses the picture and fails its write.
class Recorder : public Output {
public:
    Recorder(const std::string& name, bool refuses) : name_(name), refuses_(refuses) {}
    bool prepare_picture(EditablePicture&, CancelQuery) override
    {
        hook_log().push_back("prepare " + name_);
        return !refuses_;
    }
    bool write(const WrittenImage& image, SidecarFiles& files) override
    {
        hook_log().push_back("write " + name_);
        if (!refuses_)
            files.raw = name_ + "-" + std::to_string(image.picture.width()) + "x" + std::to_string(image.picture.height());
        return !refuses_;
    }

private:
    std::string name_;
    bool refuses_;
};

std::unique_ptr<Output> start_first(const Render&, const RenderArea&)
{
    return std::unique_ptr<Output>(new Recorder("first", false));
}
std::unique_ptr<Output> start_refusing(const Render&, const RenderArea&)
{
    return std::unique_ptr<Output>(new Recorder("refusing", true));
}
std::unique_ptr<Output> start_never(const Render&, const RenderArea&) { return nullptr; }
std::unique_ptr<Output> start_last(const Render&, const RenderArea&)
{
    return std::unique_ptr<Output>(new Recorder("last", false));
}

class TestPicture : public EditablePicture {
public:
    TestPicture(int W, int H) : W_(W), H_(H), rgb_(size_t(W) * H * 3, 0.25f) {}
    int width() const override { return W_; }
    int height() const override { return H_; }
    void read_rows(int first, int count, float* rgb) const override
    {
        std::copy(rgb_.begin() + ptrdiff_t(first) * W_ * 3, rgb_.begin() + ptrdiff_t(first + count) * W_ * 3, rgb);
    }
    void write_rows(int first, int count, const float* rgb) override
    {
        std::copy(rgb, rgb + size_t(count) * W_ * 3, rgb_.begin() + ptrdiff_t(first) * W_ * 3);
    }

private:
    int W_, H_;
    std::vector<float> rgb_;
};

std::string temporary_directory()
{
    std::string pattern = testing::TempDir() + "outputs-XXXXXX";
    std::vector<char> buffer(pattern.begin(), pattern.end());
    buffer.push_back('\0');
    const char* made = mkdtemp(buffer.data());
    return made != nullptr ? std::string(made) : std::string();
}

std::string file_text(const std::string& path)
{
    std::ifstream in(path.c_str());
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

TEST(OutputDrivers, RunTheListInOrderPreparingUntilARefusalAndWritingEveryOutput)
{
    std::vector<OutputKind> kinds = {{"first", &start_first}, {"never", &start_never}, {"refusing", &start_refusing},
                                     {"last", &start_last}};
    Render render(setup_of(plenoptic(0.5)), test_frame(), 4, 3, whole(4, 3), kinds);
    EXPECT_EQ(Names({"first", "refusing", "last"}), render.output_names());

    hook_log().clear();
    TestPicture picture(4, 3);
    EXPECT_FALSE(prepare_picture(render, picture, &no_cancel));
    EXPECT_EQ(Names({"prepare first", "prepare refusing"}), hook_log());

    hook_log().clear();
    EXPECT_FALSE(write_outputs(render, "/nonexistent/x.png", picture, &no_cancel));
    EXPECT_EQ(Names({"write first", "write refusing", "write last"}), hook_log());
}

// The metadata names what an output before it recorded (a test-only output beside the real
// metadata output).
TEST(OutputDrivers, TheMetadataNamesTheFilesTheOutputsBeforeItRecorded)
{
    std::vector<OutputKind> kinds = output_kinds();
    kinds.insert(kinds.end() - 1, OutputKind{"first", &start_first});
    CameraParams params = plenoptic(0.5);
    params.sensor.chain.given = true;  // the metadata has the raw's name only with a read-out
    std::shared_ptr<CameraSetup> setup = setup_of(params);
    setup->microimage_centres = CameraSetup::kDoNotWrite;
    Render render(setup, test_frame(), 6, 5, whole(6, 5), kinds);
    const std::string dir = temporary_directory();
    ASSERT_FALSE(dir.empty());
    TestPicture picture(6, 5);
    hook_log().clear();
    // The real raw output writes scene.raw.png, then the test-only one records its own name.
    EXPECT_TRUE(write_outputs(render, dir + "/scene.png", picture, &no_cancel));
    EXPECT_EQ(Names({"write first"}), hook_log());
    const std::string json = file_text(dir + "/scene.plenoptic.json");
    EXPECT_NE(std::string::npos, json.find("\"first-6x5\"")) << json;
    EXPECT_EQ(std::string::npos, json.find("scene.raw.png")) << json;
    EXPECT_FALSE(file_text(dir + "/scene.raw.png").empty());
    std::remove((dir + "/scene.plenoptic.json").c_str());
    std::remove((dir + "/scene.raw.png").c_str());
    std::remove(dir.c_str());
}

// ---- the depth map's per-pixel hook -------------------------------------------------------

// A made-up scene: the distance is a function of the ray (its direction's x and y), so a depth
// stored for the wrong pixel or ray shows.
class TestScene : public SceneProbe {
public:
    double first_hit(const OpticsRay& ray) override
    {
        ++hits;
        return 1000 + 100 * ray.dir.x + 10 * ray.dir.y;
    }
    void cooperate() override { ++cooperations; }
    int hits = 0;
    int cooperations = 0;
};

std::vector<float> read_depth(const std::string& path, int W, int H)
{
    std::vector<float> z(size_t(W) * H, std::numeric_limits<float>::quiet_NaN());
    Imf::InputFile file(path.c_str());
    Imf::FrameBuffer buffer;
    buffer.insert("Z", Imf::Slice(Imf::FLOAT, (char*)z.data(), sizeof(float), sizeof(float) * W));
    file.setFrameBuffer(buffer);
    file.readPixels(0, H - 1);
    return z;
}

// What the depth map must hold at (i, j): -1 where no sample passes, else the scene's distance
// along the pixel's chief ray.
float expected_depth(const PlenopticCamera& model, int i, int j)
{
    if (!model.receives_light(i, j))
        return -1.0f;
    const OpticsRay ray = model.chief_ray(i, j);
    return float(1000 + 100 * ray.dir.x + 10 * ray.dir.y);
}

TEST(DepthMapOutput, ComputesEachTracedPixelAndAContinuedRendersOwedBlocks)
{
    const int W = 12, H = 10;
    std::shared_ptr<CameraSetup> setup = setup_of(plenoptic(0.5));
    setup->depth_map = true;
    // A continued render: the top-left 6 x 4 block and rows 8-9 were finished before.
    RenderArea area = whole(W, H);
    area.untraced = {PixelRect{0, 0, 5, 3}, PixelRect{0, 8, 11, 9}};
    Render render(setup, test_frame(), W, H, area);
    ASSERT_TRUE(render.traces_pixels());
    TestScene scene;
    int traced = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const bool untraced = (i <= 5 && j <= 3) || j >= 8;
            if (!untraced) {
                render.pixel_traced(i, j, scene);
                ++traced;
            }
        }
    // The 6 rows of the two rectangles' rows, one stop check each.
    EXPECT_EQ(4 + 2, scene.cooperations);
    int lit = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            lit += render.model().receives_light(i, j) ? 1 : 0;
    EXPECT_EQ(lit, scene.hits);  // every pixel's depth once, traced or owed
    EXPECT_GT(traced, 0);

    const std::string dir = temporary_directory();
    ASSERT_FALSE(dir.empty());
    TestPicture picture(W, H);
    EXPECT_TRUE(write_outputs(render, dir + "/scene.png", picture, &no_cancel));
    const std::vector<float> z = read_depth(dir + "/scene.depth.exr", W, H);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            EXPECT_EQ(expected_depth(render.model(), i, j), z[size_t(j) * W + i]) << i << ", " << j;
    EXPECT_NE(std::string::npos, file_text(dir + "/scene.plenoptic.json").find("\"scene.depth.exr\""));
    std::remove((dir + "/scene.depth.exr").c_str());
    std::remove((dir + "/scene.plenoptic.json").c_str());
    std::remove(dir.c_str());
}

TEST(DepthMapOutput, RowsNeverRenderedReadMinusOne)
{
    const int W = 8, H = 6;
    std::shared_ptr<CameraSetup> setup = setup_of(thin_lens_camera(50, 4, 52));
    setup->depth_map = true;
    Render render(setup, test_frame(), W, H, RenderArea{PixelRect{0, 2, W - 1, 3}, {}});
    TestScene scene;
    for (int j = 2; j <= 3; ++j)
        for (int i = 0; i < W; ++i)
            render.pixel_traced(i, j, scene);
    const std::string dir = temporary_directory();
    ASSERT_FALSE(dir.empty());
    TestPicture picture(W, H);
    EXPECT_TRUE(write_outputs(render, dir + "/part.png", picture, &no_cancel));
    const std::vector<float> z = read_depth(dir + "/part.depth.exr", W, H);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            EXPECT_EQ(j == 2 || j == 3 ? expected_depth(render.model(), i, j) : -1.0f, z[size_t(j) * W + i]);
    std::remove((dir + "/part.depth.exr").c_str());
    std::remove((dir + "/part.plenoptic.json").c_str());
    std::remove(dir.c_str());
}

// ---- the hand-over, keyed by the view --------------------------------------------------

TEST(RenderHandOver, EachViewTakesItsOwnRenderOnce)
{
    const std::shared_ptr<CameraSetup> setup = setup_of(plenoptic(0.5));
    std::shared_ptr<Render> a = std::make_shared<Render>(setup, test_frame(), 4, 4, whole(4, 4));
    std::shared_ptr<Render> b = std::make_shared<Render>(setup, test_frame(), 6, 6, whole(6, 6));
    publish_render(101, a);
    publish_render(102, b);  // a second render does not replace the first view's
    EXPECT_EQ(b, published_render(102));
    EXPECT_EQ(a, take_published_render(101));
    EXPECT_EQ(nullptr, take_published_render(101));
    EXPECT_EQ(b, take_published_render(102));
    EXPECT_EQ(nullptr, published_render(103));  // a view that published nothing

    // A view that renders again hands over its latest render.
    publish_render(104, a);
    publish_render(104, b);
    EXPECT_EQ(b, take_published_render(104));
}

TEST(RenderHandOver, ARenderLivesOnlyAsLongAsItsViewHoldsIt)
{
    std::shared_ptr<Render> render =
        std::make_shared<Render>(setup_of(plenoptic(0.5)), test_frame(), 4, 4, whole(4, 4));
    std::weak_ptr<Render> watch = render;
    publish_render(201, render);
    render.reset();  // the view closed without writing its image
    EXPECT_TRUE(watch.expired());
    EXPECT_EQ(nullptr, take_published_render(201));
}

} // namespace
} // namespace plenoptic
