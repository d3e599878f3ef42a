// SPDX-License-Identifier: AGPL-3.0-or-later
// Diffraction as a stage of the outputs: before the image is written, the picture is convolved
// with the camera's Airy patterns (sensor/diffraction.h), in linear light, so the image, its raw
// and everything read from it carry it. Wanted when the camera's diffraction is applied.

#include <cstdio>

#include "plenoptic/sensor/diffraction.h"
#include "povray_glue/outputs/output.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {

namespace {

class DiffractionStage : public Output {
public:
    DiffractionStage(const Render& render, const Diffraction& diffraction) : render_(render), diffraction_(diffraction) {}

    bool prepare_picture(EditablePicture& picture, CancelQuery cancelled) override
    {
        const int W = picture.width(), H = picture.height();
        if (W != render_.width() || H != render_.height())
            return true;
        if (render_.continued()) {
            // The rows the earlier run wrote were diffracted already: a second convolution would
            // blur them twice. The image file stays as the earlier run left it.
            std::fprintf(stderr, "plenoptic camera: diffraction cannot continue a render (+C): the part rendered "
                                 "before was diffracted already; render the image again without +C. No image written.\n");
            return false;
        }
        const std::vector<AiryKernel> kernels = channel_kernels(render_.model(), diffraction_);
        if (size_t(W) * H >= 4000000)
            std::fprintf(stderr, "plenoptic camera: diffraction: convolving %d x %d pixels with Airy kernels of %d x %d "
                                 "pixels (red)\n", W, H, 2 * kernels[0].kx + 1, 2 * kernels[0].ky + 1);
        // In place, band by band: the picture's rows are read and written back as the convolution
        // goes (sensor/diffraction.h), never copied as a whole.
        const RowReader read = [&](int first, int count, float* to) {
            picture.read_rows(first, count, to);
            return true;
        };
        const RowWriter write = [&](int first, int count, const float* from) {
            picture.write_rows(first, count, from);
            return true;
        };
        if (!convolve_rows(W, H, 3, kernels.data(), read, write, cancelled)) {
            std::fprintf(stderr, "plenoptic camera: cancelled while applying diffraction: the image is not written "
                                 "(it would not be what the camera records).\n");
            return false;
        }
        return true;
    }

private:
    const Render& render_;
    const Diffraction diffraction_;
};

} // namespace

std::unique_ptr<Output> start_diffraction(const Render& render, const RenderArea&)
{
    const Diffraction diffraction = diffraction_of(render.model(), render.setup().params.diffraction);
    if (!diffraction.applied)
        return nullptr;
    return std::unique_ptr<Output>(new DiffractionStage(render, diffraction));
}

} // namespace plenoptic
