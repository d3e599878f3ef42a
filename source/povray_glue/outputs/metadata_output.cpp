// SPDX-License-Identifier: AGPL-3.0-or-later
// The metadata output: <image>.plenoptic.json (truth/metadata.h), the camera of the image written
// and the files the outputs before it wrote. Always wanted, and last in the list; written even
// when an earlier output failed or was cancelled (it then names no file for it).

#include "povray_glue/outputs/files.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {

namespace {

class MetadataOutput : public Output {
public:
    explicit MetadataOutput(const Render& render) : render_(render) {}

    bool write(const WrittenImage& image, SidecarFiles& files) override
    {
        const std::string json = metadata_json(image.camera, render_.setup().params, render_.frame(), files);
        return write_file_atomically("metadata", image.beside(".plenoptic.json"), json);
    }

private:
    const Render& render_;
};

} // namespace

std::unique_ptr<Output> start_metadata(const Render& render, const RenderArea&)
{
    return std::unique_ptr<Output>(new MetadataOutput(render));
}

} // namespace plenoptic
