// SPDX-License-Identifier: AGPL-3.0-or-later
// The front end's hooks for a plenoptic render's outputs (see plenoptic_sidecar.h): POV-Ray's
// image as the outputs' picture, and the render of the view.

#include "povray_glue/plenoptic_sidecar.h"

#include <cstdio>
#include <memory>
#include <vector>

#include "povray_glue/outputs/output.h"
#include "povray_glue/outputs/render.h"
#include "povray_glue/plenoptic_cancel.h"

#include "base/image/colourspace.h"
#include "base/image/image.h"

namespace plenoptic {

namespace {

// POV-Ray's image, read in linear light.
class PovPicture : public Picture {
public:
    PovPicture(const pov_base::Image& image, const pov_base::GammaCurve* working_gamma)
        : image_(image), working_gamma_(working_gamma) {}

    int width() const override { return int(image_.GetWidth()); }
    int height() const override { return int(image_.GetHeight()); }

    void read_rows(int first, int count, float* rgb) const override
    {
        const int W = width();
        for (int r = 0; r < count; ++r)
            for (int i = 0; i < W; ++i) {
                float* pixel = rgb + (size_t(r) * W + i) * 3;
                image_.GetRGBValue(unsigned(i), unsigned(first + r), pixel[0], pixel[1], pixel[2]);
                if (working_gamma_ != nullptr)
                    for (int c = 0; c < 3; ++c)
                        pixel[c] = working_gamma_->Decode(pixel[c]);
            }
    }

private:
    const pov_base::Image& image_;
    const pov_base::GammaCurve* working_gamma_;
};

// ... and written back, before the front end writes it.
class EditablePovPicture : public EditablePicture {
public:
    EditablePovPicture(pov_base::Image& image, const pov_base::GammaCurve* working_gamma)
        : image_(image), working_gamma_(working_gamma), reader_(image, working_gamma) {}

    int width() const override { return reader_.width(); }
    int height() const override { return reader_.height(); }
    void read_rows(int first, int count, float* rgb) const override { reader_.read_rows(first, count, rgb); }

    void write_rows(int first, int count, const float* rgb) override
    {
        const int W = width();
        for (int r = 0; r < count; ++r)
            for (int i = 0; i < W; ++i) {
                const unsigned x = unsigned(i), y = unsigned(first + r);
                float red, green, blue, f, t;
                image_.GetRGBFTValue(x, y, red, green, blue, f, t);
                float value[3];
                for (int c = 0; c < 3; ++c) {
                    value[c] = rgb[(size_t(r) * W + i) * 3 + c];
                    if (working_gamma_ != nullptr)
                        value[c] = working_gamma_->Encode(value[c]);
                }
                image_.SetRGBFTValue(x, y, value[0], value[1], value[2], f, t);
            }
    }

private:
    pov_base::Image& image_;
    const pov_base::GammaCurve* working_gamma_;
    PovPicture reader_;
};

} // namespace

bool sidecar_prepare_image(int view, pov_base::Image& image, const pov_base::GammaCurve* working_gamma)
{
    const std::shared_ptr<Render> render = published_render(view);
    if (!render)
        return true;
    EditablePovPicture picture(image, working_gamma);
    return prepare_picture(*render, picture, render_cancel_requested);
}

bool sidecar_write(int view, const std::string& image_path, const pov_base::Image& image,
                   const pov_base::GammaCurve* working_gamma)
{
    const std::shared_ptr<Render> render = take_published_render(view);
    if (!render)
        return true;
    // +O- : POV-Ray writes the image to standard output under the name "stdout"; there is no
    // file beside which the metadata could go.
    if (image_path == "stdout" || image_path == "stderr") {
        std::fprintf(stderr, "plenoptic camera: the image went to standard output (+O-), so no metadata or "
                             "depth map is written; give +O a file name to get them.\n");
        return true;
    }
    const PovPicture picture(image, working_gamma);
    return write_outputs(*render, image_path, picture, render_cancel_requested);
}

} // namespace plenoptic
