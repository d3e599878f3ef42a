// SPDX-License-Identifier: AGPL-3.0-or-later
// The list of a render's outputs, in the order they run, and the drivers that run it (output.h).

#include "povray_glue/outputs/output.h"

#include "povray_glue/outputs/files.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {

// One line per output: X(name) stands for start_<name>, defined in the output's own file. The
// order is the order in which they run, and in which their messages appear.
#define PLENOPTIC_OUTPUT_LIST(X)                                                                      \
    X(diffraction)   /* before the image is written: the picture through the camera's diffraction */ \
    X(depth_map)     /* <image>.depth.exr, computed as the pixels are traced */                       \
    X(virtual_depth) /* <image>.virtual_depth.exr of a focused camera, from the depth map */           \
    X(microimages)   /* <image>.microimages.csv */                                                     \
    X(raw)           /* <image>.raw.png, the picture through the sensor's read-out */                  \
    X(white_images)  /* <image>.white.png, <image>.white.f<N>.png */                                   \
    X(metadata)      /* <image>.plenoptic.json: last, since it names the files written before it */

#define PLENOPTIC_DECLARE_OUTPUT(name) std::unique_ptr<Output> start_##name(const Render& render, const RenderArea& area);
PLENOPTIC_OUTPUT_LIST(PLENOPTIC_DECLARE_OUTPUT)
#undef PLENOPTIC_DECLARE_OUTPUT

const std::vector<OutputKind>& output_kinds()
{
#define PLENOPTIC_OUTPUT_KIND(name) OutputKind{#name, &start_##name},
    static const std::vector<OutputKind> kinds = {PLENOPTIC_OUTPUT_LIST(PLENOPTIC_OUTPUT_KIND)};
#undef PLENOPTIC_OUTPUT_KIND
    return kinds;
}

std::string WrittenImage::beside(const std::string& suffix) const { return replace_extension(path, suffix); }

bool prepare_picture(Render& render, EditablePicture& picture, CancelQuery cancelled)
{
    for (const std::unique_ptr<Output>& output : render.outputs())
        if (!output->prepare_picture(picture, cancelled))
            return false;
    return true;
}

bool write_outputs(Render& render, const std::string& image_path, const Picture& picture, CancelQuery cancelled)
{
    const WrittenImage image(image_path, picture, with_film(render.model(), picture.width(), picture.height()),
                             cancelled);
    SidecarFiles files;
    bool ok = true;
    for (const std::unique_ptr<Output>& output : render.outputs())
        if (!output->write(image, files))
            ok = false;
    return ok;
}

} // namespace plenoptic
