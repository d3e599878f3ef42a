// SPDX-License-Identifier: AGPL-3.0-or-later
// The microimage centres output: <image>.microimages.csv, the microimages of a white scene through
// this camera (truth/microimages.h), and their summary in the metadata. Needs a main lens and an
// array; `microimage_centres` on or off, and by default written only where the centres leave the
// lattice the metadata gives (a traced lens, a thin lens with distortion, an array with manufacturing
// errors).

#include <cstdio>

#include "plenoptic/truth/microimages.h"
#include "povray_glue/outputs/files.h"
#include "povray_glue/outputs/render.h"

namespace plenoptic {

namespace {

class MicroimagesOutput : public Output {
public:
    bool write(const WrittenImage& image, SidecarFiles& files) override
    {
        const PlenopticCamera& model = image.camera;
        const MicroimageOptions options = default_microimage_options();
        // Seconds for large arrays (a fraction of a millisecond a lens and thread behind a real lens): say
        // how far.
        const MicroimageProgress progress = [](std::size_t done, std::size_t total) {
            if (total >= 20000)
                std::fprintf(stderr, "plenoptic camera: microimage centres: %zu of %zu lenses\n", done, total);
        };
        MicroimageWork work;
        const std::vector<MicroimageTruth> truth =
            microimage_truth(model, options, progress, image.cancelled, nullptr, &work);
        const std::string path = image.beside(".microimages.csv");
        if (image.cancelled()) {
            std::fprintf(stderr, "plenoptic camera: cancelled: no microimage centres written (%s); the metadata says "
                                 "\"microimages\": null.\n", path.c_str());
            return true;
        }
        MicroimageSummary summary = summarise_microimages(model, truth, options, base_name(path));
        summary.work = work;
        // With spectral sampling, the same lenses at each channel's wavelength.
        std::vector<std::vector<MicroimageTruth>> channels;
        if (model.spectral) {
            summary.per_channel = true;
            channel_wavelengths_nm(model.spec.spectral, summary.channel_wavelengths_nm);
            for (int c = 0; c < 3 && !image.cancelled(); ++c) {
                const PlenopticCamera at = at_wavelength(model, summary.channel_wavelengths_nm[c]);
                // Nothing disperses (the same lens and microlens objects): the d line's centres.
                const bool same = at.lens == model.lens && at.array.microlens == model.array.microlens;
                channels.push_back(same ? truth : microimage_truth(model, options, progress, image.cancelled, &at));
            }
            if (image.cancelled()) {
                std::fprintf(stderr, "plenoptic camera: cancelled: no microimage centres written (%s); the metadata "
                                     "says \"microimages\": null.\n", path.c_str());
                return true;
            }
        }
        // Written as it is made, a few thousand lenses at a time (the whole text of a Lytro-class
        // raw would be some 25 MB held at once).
        const std::size_t kPiece = 4096;
        std::size_t written = 0;
        bool header = false;
        const bool per_channel = channels.size() == 3;
        const bool ok = write_file_atomically("microimage centres", path, [&](std::string* piece) {
            if (!header) {
                header = true;
                *piece = microimages_csv_header(model, per_channel);
                return true;
            }
            if (written >= truth.size())
                return false;
            *piece = microimages_csv_lines(model, truth, summary.fit, channels, written, written + kPiece);
            written += kPiece;
            return true;
        });
        if (!ok)
            return false;
        summary_.reset(new MicroimageSummary(summary));
        files.microimages = summary_.get();
        return true;
    }

private:
    std::unique_ptr<MicroimageSummary> summary_;  // what the metadata names, once written
};

} // namespace

std::unique_ptr<Output> start_microimages(const Render& render, const RenderArea&)
{
    const PlenopticCamera& model = render.model();
    const CameraSetup::MicroimageCentres asked = render.setup().microimage_centres;
    const bool off_lattice = (model.lens && model.lens->traced()) || model.distortion() || model.array.errors;
    if (model.array.grid == GridType::None || !model.lens ||
        !(asked == CameraSetup::kWrite || (asked == CameraSetup::kDefault && off_lattice)))
        return nullptr;
    return std::unique_ptr<Output>(new MicroimagesOutput());
}

} // namespace plenoptic
