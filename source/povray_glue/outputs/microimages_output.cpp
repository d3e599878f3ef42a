// SPDX-License-Identifier: AGPL-3.0-or-later
// The microimage centres output: <image>.microimages.csv, the microimages of a white scene through
// this camera (truth/microimages.h), and their summary in the metadata. Needs a main lens and an
// array; `microimage_centres` on or off, and by default written only where the centres leave the
// lattice the metadata gives (a traced lens, a thin lens with distortion, an array with manufacturing
// errors). `microimage_error_anchors N` corrects refracting microlenses with errors from Jacobian
// anchors N lenses apart instead of measuring each.

#include <cstdio>

#include "plenoptic/array/refracting_microlens.h"
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
        MicroimageOptions options = default_microimage_options();
        options.error_anchor_step = error_anchors_;
        warn_if_slow(model);
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

    explicit MicroimagesOutput(int error_anchors) : error_anchors_(error_anchors) {}

private:
    // Refracting microlenses with manufacturing errors, each measured (150 ms of CPU a lens behind
    // the 22 mm wide-angle: BENCHMARKS.md, "Refracting microlenses with errors, corrected"): from
    // some 20,000 lenses, hours; say so before they start, and name the keyword that takes minutes.
    void warn_if_slow(const PlenopticCamera& model) const
    {
        const MicrolensArray& array = model.array;
        if (error_anchors_ != 0 || !array.errors || !array.microlens || !refracting_shape(*array.microlens))
            return;
        const Film film = model.sensor.film;
        const double lenses = film.width * model.sensor.pixel_size_mm[0] * film.height * model.sensor.pixel_size_mm[1] /
                              (array.pitch_mm * array.row_spacing_mm());
        if (lenses >= 20000)
            std::fprintf(stderr, "plenoptic camera: microimage centres: about %.0f refracting microlenses with "
                                 "manufacturing errors, each measured (some 0.1 s of CPU a lens: hours); "
                                 "microimage_error_anchors 64 corrects them from anchors instead (minutes, within "
                                 "about 0.01 px), microimage_centres off skips them\n", lenses);
    }

    int error_anchors_;  // `microimage_error_anchors`
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
    return std::unique_ptr<Output>(new MicroimagesOutput(render.setup().microimage_error_anchors));
}

} // namespace plenoptic
