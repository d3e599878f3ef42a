// SPDX-License-Identifier: AGPL-3.0-or-later
// Metadata and depth-map files beside a plenoptic render (see plenoptic_sidecar.h).

#include "povray_glue/plenoptic_sidecar.h"

#include "povray_glue/plenoptic_cancel.h"
#include "povray_glue/plenoptic_raw_png.h"
#include "povray_glue/plenoptic_render.h"
#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/truth/virtual_depth.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include "base/image/colourspace.h"
#include "base/image/image.h"

namespace plenoptic {

namespace {

std::string replace_extension(const std::string& path, const std::string& suffix)
{
    const size_t slash = path.find_last_of('/');
    const size_t dot = path.find_last_of('.');
    const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
    return (has_ext ? path.substr(0, dot) : path) + suffix;
}

std::string directory_of(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string(".") : (slash == 0 ? std::string("/") : path.substr(0, slash));
}

// A new, empty file with a short name in the directory of `path` (so renaming it onto `path` is
// atomic, and a long output name does not become too long a temporary one); empty on failure.
std::string temporary_beside(const std::string& path)
{
    std::string name = directory_of(path) + "/.plenoptic-XXXXXX";
    std::vector<char> buffer(name.begin(), name.end());
    buffer.push_back('\0');
    const int fd = mkstemp(buffer.data());
    if (fd < 0)
        return "";
    // mkstemp creates the file for its owner only; the files beside the image get the permissions
    // the image gets (0666 less the umask), as any file the program writes.
    const mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, 0666 & ~mask);
    close(fd);
    return std::string(buffer.data());
}

void report_failure(const char* what, const std::string& path, int error)
{
    std::fprintf(stderr, "plenoptic camera: cannot write %s %s: %s\n", what, path.c_str(), std::strerror(error));
}

bool write_text_atomically(const char* what, const std::string& path, const std::string& text)
{
    const std::string tmp = temporary_beside(path);
    if (tmp.empty()) {
        report_failure(what, path, errno);
        return false;
    }
    FILE* f = std::fopen(tmp.c_str(), "wb");
    if (f == nullptr) {
        report_failure(what, path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !ok || std::rename(tmp.c_str(), path.c_str()) != 0) {
        report_failure(what, path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    return true;
}

// Writes a one-channel float EXR row by row (memory: one row): fill(j, row) fills row j and
// returns false to stop (cancelled: nothing is written). `what` names the file in messages.
template <class Fill>
bool write_float_exr(const std::string& path, const char* what, const char* channel, int W, int H, Fill fill)
{
    const std::string tmp = temporary_beside(path);
    if (tmp.empty()) {
        report_failure(what, path, errno);
        return false;
    }
    bool complete = true;
    try {
        Imf::Header header(W, H);
        header.channels().insert(channel, Imf::Channel(Imf::FLOAT));
        Imf::OutputFile file(tmp.c_str(), header);
        std::vector<float> row(size_t(W), 0.0f);
        for (int j = 0; j < H && complete; ++j) {
            complete = fill(j, row.data());
            // The slice's base is where pixel (0, 0) would be, so that row j starts at `row`.
            Imf::FrameBuffer buffer;
            buffer.insert(channel, Imf::Slice(Imf::FLOAT, (char*)(row.data()) - sizeof(float) * size_t(W) * j,
                                              sizeof(float), sizeof(float) * W));
            file.setFrameBuffer(buffer);
            if (complete)
                file.writePixels(1);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "plenoptic camera: cannot write %s %s: %s\n", what, path.c_str(), e.what());
        std::remove(tmp.c_str());
        return false;
    }
    if (!complete) {
        std::remove(tmp.c_str());
        return false;
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        report_failure(what, path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    return true;
}

// The depth map, -1 in rows never rendered.
bool write_depth_exr(const std::string& path, const DepthMap& depth)
{
    const int W = depth.width();
    return write_float_exr(path, "depth map", "Z", W, depth.height(), [&](int j, float* row) {
        const float* rendered = depth.row(j);
        for (int i = 0; i < W; ++i)
            row[i] = rendered != nullptr ? rendered[i] : -1.0f;
        return true;
    });
}

// A focused camera's virtual depth per pixel, from the depth map (NaN where it is -1 or was not
// rendered). Stops on Ctrl-C (no file).
bool write_virtual_depth_exr(const std::string& path, const Model& model, const DepthMap& depth)
{
    const int W = depth.width(), H = depth.height();
    if (size_t(W) * H >= 4000000)
        std::fprintf(stderr, "plenoptic camera: virtual depth of %d x %d pixels\n", W, H);
    return write_float_exr(path, "virtual depth map", "V", W, H, [&](int j, float* row) {
        if (render_cancel_requested())
            return false;
        const float* rendered = depth.row(j);
        for (int i = 0; i < W; ++i)
            row[i] = pixel_virtual_depth(model, i, j, rendered != nullptr ? rendered[i] : -1.0f);
        return true;
    });
}

// The picture's R, G, B in linear light, interleaved, rows from the top.
std::vector<float> linear_rgb(const pov_base::Image& image, const pov_base::GammaCurve* working_gamma)
{
    const int W = int(image.GetWidth()), H = int(image.GetHeight());
    std::vector<float> linear(size_t(W) * H * 3);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            float* rgb = &linear[(size_t(j) * W + i) * 3];
            image.GetRGBValue(unsigned(i), unsigned(j), rgb[0], rgb[1], rgb[2]);
            if (working_gamma != nullptr)
                for (int c = 0; c < 3; ++c)
                    rgb[c] = working_gamma->Decode(rgb[c]);
        }
    return linear;
}

std::string base_name(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

} // namespace

std::string metadata_path_for(const std::string& image_path) { return replace_extension(image_path, ".plenoptic.json"); }
std::string depth_path_for(const std::string& image_path) { return replace_extension(image_path, ".depth.exr"); }
std::string virtual_depth_path_for(const std::string& image_path)
{
    return replace_extension(image_path, ".virtual_depth.exr");
}
std::string microimages_path_for(const std::string& image_path)
{
    return replace_extension(image_path, ".microimages.csv");
}

std::string raw_path_for(const std::string& image_path) { return replace_extension(image_path, ".raw.png"); }

bool sidecar_prepare_image(pov_base::Image& image, const pov_base::GammaCurve* working_gamma)
{
    const std::shared_ptr<Render> render = published_render();
    if (!render)
        return true;
    const int W = int(image.GetWidth()), H = int(image.GetHeight());
    const Diffraction diffraction = diffraction_of(render->model(), render->setup().params.diffraction);
    if (!diffraction.applied || W != render->width() || H != render->height())
        return true;
    if (render->continued()) {
        // The rows the earlier run wrote were diffracted already: a second convolution would blur
        // them twice. The image file stays as the earlier run left it.
        std::fprintf(stderr, "plenoptic camera: diffraction cannot continue a render (+C): the part rendered "
                             "before was diffracted already; render the image again without +C. No image written.\n");
        return false;
    }
    std::vector<float> linear = linear_rgb(image, working_gamma);
    const std::vector<AiryKernel> kernels = channel_kernels(render->model(), diffraction);
    if (size_t(W) * H >= 4000000)
        std::fprintf(stderr, "plenoptic camera: diffraction: convolving %d x %d pixels with Airy kernels of %d x %d "
                             "pixels (red)\n", W, H, 2 * kernels[0].kx + 1, 2 * kernels[0].ky + 1);
    if (!convolve_channels(linear, W, H, 3, kernels.data(), render_cancel_requested)) {
        std::fprintf(stderr, "plenoptic camera: cancelled while applying diffraction: the image is not written "
                             "(it would not be what the camera records).\n");
        return false;
    }
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            float r, g, b, f, t;
            image.GetRGBFTValue(unsigned(i), unsigned(j), r, g, b, f, t);
            float* rgb = &linear[(size_t(j) * W + i) * 3];
            if (working_gamma != nullptr)
                for (int c = 0; c < 3; ++c)
                    rgb[c] = working_gamma->Encode(rgb[c]);
            image.SetRGBFTValue(unsigned(i), unsigned(j), rgb[0], rgb[1], rgb[2], f, t);
        }
    return true;
}

bool sidecar_write(const std::string& image_path, const pov_base::Image& image, const pov_base::GammaCurve* working_gamma)
{
    const int W = int(image.GetWidth()), H = int(image.GetHeight());
    const std::shared_ptr<Render> render = take_published_render();
    if (!render)
        return true;
    // +O- : POV-Ray writes the image to standard output under the name "stdout"; there is no
    // file beside which the metadata could go.
    if (image_path == "stdout" || image_path == "stderr") {
        std::fprintf(stderr, "plenoptic camera: the image went to standard output (+O-), so no metadata or "
                             "depth map is written; give +O a file name to get them.\n");
        return true;
    }
    bool ok = true;
    SidecarFiles files;
    // The camera with the film of the image written (the render's, unless the front end wrote
    // another size).
    const Model model = with_film(render->model(), W, H);
    if (render->depth() != nullptr && W == render->width() && H == render->height()) {
        const long long unknown = render->backfill() ? render->backfill()->pixels_not_handed_out() : 0;
        if (unknown > 0)
            std::fprintf(stderr, "plenoptic camera: the depth of %lld pixels rendered before the render was "
                                 "continued (+C) is unknown: this render traced no pixel that could compute it; "
                                 "they read -1 in the depth map.\n", unknown);
        const std::string depth_path = depth_path_for(image_path);
        if (write_depth_exr(depth_path, *render->depth()))
            files.depth_map = base_name(depth_path);
        else
            ok = false;
        if (is_focused_camera(model)) {
            const std::string path = virtual_depth_path_for(image_path);
            if (write_virtual_depth_exr(path, model, *render->depth()))
                files.virtual_depth_map = base_name(path);
            else if (render_cancel_requested())
                std::fprintf(stderr, "plenoptic camera: cancelled: no virtual depth map written (%s).\n", path.c_str());
            else
                ok = false;
        }
    }
    // The microimages of a white scene through this camera (a main lens and an array): by default
    // only where they leave the lattice the metadata gives (docs/real-lenses.md).
    const CameraSetup::MicroimageCentres asked = render->setup().microimage_centres;
    const bool off_lattice = (model.lens && model.lens->traced()) || model.has_distortion;
    std::unique_ptr<MicroimageSummary> microimages;
    if (model.grid != GridType::None && model.lens &&
        (asked == CameraSetup::kWrite || (asked == CameraSetup::kDefault && off_lattice))) {
        const MicroimageOptions options = default_microimage_options();
        // Seconds for large arrays (about 0.5 ms a lens and thread behind a real lens): say how far.
        const MicroimageProgress progress = [](std::size_t done, std::size_t total) {
            if (total >= 20000)
                std::fprintf(stderr, "plenoptic camera: microimage centres: %zu of %zu lenses\n", done, total);
        };
        const std::vector<MicroimageTruth> truth = microimage_truth(model, options, progress, render_cancel_requested);
        const std::string path = microimages_path_for(image_path);
        if (render_cancel_requested()) {
            std::fprintf(stderr, "plenoptic camera: cancelled: no microimage centres written (%s); the metadata says "
                                 "\"microimages\": null.\n", path.c_str());
        } else {
            MicroimageSummary summary = summarise_microimages(model, truth, options, base_name(path));
            if (write_text_atomically("microimage centres", path, microimages_csv(model, truth, summary.fit)))
                microimages.reset(new MicroimageSummary(summary));
            else
                ok = false;
        }
    }
    // The sensor's raw: the rendered picture (linear) through the read-out chain.
    std::string raw_file;
    const SensorChainParams& chain = render->setup().params.sensor.chain;
    if (chain.given) {
        const std::vector<float> linear = linear_rgb(image, working_gamma);
        const bool mosaic = chain.bayer != BayerPattern::None;
        const std::string png = raw_png(sensor_raw(chain, linear, W, H), W, H, mosaic ? 1 : 3, chain.bit_depth);
        const std::string path = raw_path_for(image_path);
        if (png.empty()) {
            std::fprintf(stderr, "plenoptic camera: cannot encode the raw %s\n", path.c_str());
            ok = false;
        } else if (write_text_atomically("raw", path, png)) {
            raw_file = base_name(path);
        } else {
            ok = false;
        }
    }
    // White images: the camera alone in front of a white diffuser, at its own aperture or at each
    // f-number asked for; through the read-out when there is one (its own frame of noise), unless
    // noise_free.
    std::unique_ptr<std::vector<WhiteImageFile>> whites;
    const WhiteImageRequest& white = render->setup().white_image;
    if (white.given) {
        whites.reset(new std::vector<WhiteImageFile>());
        const CameraParams& params = render->setup().params;
        const int count = white.f_numbers.empty() ? 1 : int(white.f_numbers.size());
        for (int k = 0; k < count && !render_cancel_requested(); ++k) {
            const bool own = white.f_numbers.empty();
            const double f_number = own ? model.f_number : white.f_numbers[size_t(k)];
            std::unique_ptr<Model> other;
            if (!own)
                other.reset(new Model(with_f_number(model, f_number)));
            const Model& optics = own ? model : *other;
            const std::vector<float> values = white_image(optics, render_cancel_requested);
            if (values.empty())
                break;  // cancelled
            // R, G and B of the grey white image, where they are needed: diffraction differs by
            // colour (the white image is then RGB), and the read-out reads three channels.
            const Diffraction diffraction = diffraction_of(optics, params.diffraction);
            const bool raw = chain.given && !white.noise_free;
            std::vector<float> rgb;
            if (diffraction.applied || raw) {
                rgb.resize(values.size() * 3);
                for (size_t p = 0; p < values.size(); ++p)
                    rgb[3 * p] = rgb[3 * p + 1] = rgb[3 * p + 2] = values[p];
            }
            if (diffraction.applied) {
                const std::vector<AiryKernel> kernels = channel_kernels(optics, diffraction);
                if (!convolve_channels(rgb, W, H, 3, kernels.data(), render_cancel_requested))
                    break;  // cancelled
            }
            double scale = 1;
            std::string png;
            if (raw) {
                SensorChainParams frame = chain;
                frame.seed = chain.seed ^ (0x7768697465000000ULL + std::uint64_t(k + 1));  // "white": its own noise
                png = raw_png(sensor_raw(frame, rgb, W, H), W, H, chain.bayer != BayerPattern::None ? 1 : 3, chain.bit_depth);
            } else {
                // Irradiance can exceed 1 (overlap at a microimage's rim, a lens cell's corners):
                // divided by a power of two so that nothing clips, recorded as the entry's scale.
                const std::vector<float>& source = diffraction.applied ? rgb : values;
                float largest = 0;
                for (float v : source)
                    largest = std::max(largest, v);
                while (scale < largest && scale < 65536)
                    scale *= 2;
                std::vector<std::uint16_t> linear(source.size());
                for (size_t p = 0; p < source.size(); ++p)
                    linear[p] = std::uint16_t(std::lround(std::min(1.0, std::max(0.0, source[p] / scale)) * 65535.0));
                png = raw_png(linear, W, H, diffraction.applied ? 3 : 1, 16);
            }
            const std::string path = replace_extension(image_path, white_image_suffix(white, k));
            if (!png.empty() && write_text_atomically("white image", path, png)) {
                WhiteImageFile file;
                file.file = base_name(path);
                file.f_number = f_number;
                file.raw = raw;
                file.scale = scale;
                whites->push_back(file);
            } else {
                ok = false;
            }
        }
        if (render_cancel_requested())
            std::fprintf(stderr, "plenoptic camera: cancelled: white images not all written.\n");
    }
    files.microimages = microimages.get();
    files.raw = raw_file;
    files.white_images = whites.get();
    const std::string json = metadata_json(model, render->setup().params, render->frame(), files);
    if (!write_text_atomically("metadata", metadata_path_for(image_path), json))
        ok = false;
    return ok;
}

} // namespace plenoptic
