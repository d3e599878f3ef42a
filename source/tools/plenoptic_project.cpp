// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic-project: where 3-D points image in a plenoptic render, from its metadata file.
//
//   plenoptic-project [--fraction] [--blur] [--wavelength NM] METADATA.json X Y Z [X Y Z ...]
//   plenoptic-project [--fraction] [--blur] [--wavelength NM] METADATA.json - < points.txt
//
// Points are in scene units, world frame. Output: for each point, one line per image,
// "point_index lens_k lens_l u v" (lens in row form; u, v in pixels, the centre of pixel
// (column i, row j) at (i, j), as docs/metadata.md defines). A point that images nowhere
// (behind the camera, outside the picture, seen by no lens) prints no line. --fraction adds a
// sixth column: the part of the point's light through the main aperture in that image.
// --wavelength projects through the camera at that wavelength (at_wavelength: the glass of the
// main lens and the microlenses there, every position as rendered); without it, the d line.

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "plenoptic_metadata_reader.h"
#include "plenoptic/sensor/spectral_response.h"
#include "plenoptic/truth/blur.h"

namespace {

const char* kUsage =
    "usage: plenoptic-project [--fraction] [--blur] [--wavelength NM] METADATA.json X Y Z [X Y Z ...]\n"
    "       plenoptic-project [--fraction] [--blur] [--wavelength NM] METADATA.json -   (points from standard input, three numbers each)\n"
    "Projects world points (scene units) into the render described by METADATA.json (the\n"
    "<image>.plenoptic.json a plenoptic render writes) and prints, for each point, one line per\n"
    "image of it: point_index lens_k lens_l u v\n"
    "  point_index  0-based, in the order given\n"
    "  lens_k lens_l the microlens in row form ((0, 0) without an array)\n"
    "  u v          pixel coordinates, centre of pixel (column i, row j) at (i, j), v downwards\n"
    "  --fraction   adds a sixth column: the part of the point's light through the main aperture\n"
    "               that arrives in that image (1 where each image is a single ray: pinholes)\n"
    "  --blur       adds a column (after the fraction, if asked for): the signed radius in pixels of\n"
    "               the point's defocus blur through that microlens, libpleno's blur-aware point model\n"
    "               r = (pitch / 2) d (1/f - 1/a - 1/d) (docs/ground-truth.md); nan where undefined\n"
    "  --wavelength NM  projects through the camera at NM nanometres (380 to 720): the glass of a\n"
    "               dispersing main lens and microlenses at their indices there, every position as\n"
    "               rendered; without it, at the d line (587.56 nm), as the render's own truth\n"
    "Exit status: 0 done, 2 bad usage, unreadable or invalid metadata, or a malformed number.\n";

bool parse_number(const std::string& text, double* value)
{
    if (text.empty())
        return false;
    errno = 0;
    char* end = nullptr;
    *value = std::strtod(text.c_str(), &end);
    return end == text.c_str() + text.size() && errno != ERANGE && std::isfinite(*value);
}

int fail(const std::string& message)
{
    std::fprintf(stderr, "plenoptic-project: %s\n", message.c_str());
    return 2;
}

} // namespace

int main(int argc, char** argv)
{
    std::vector<std::string> args(argv + 1, argv + argc);
    if (!args.empty() && (args[0] == "-h" || args[0] == "--help")) {
        std::fputs(kUsage, stdout);
        return 0;
    }
    bool with_fraction = false, with_blur = false, with_wavelength = false;
    double wavelength_nm = 0;
    while (!args.empty() && (args[0] == "--fraction" || args[0] == "--blur" || args[0] == "--wavelength")) {
        if (args[0] == "--wavelength") {
            if (args.size() < 2 || !parse_number(args[1], &wavelength_nm))
                return fail("--wavelength needs a number of nanometres" + (args.size() < 2 ? std::string() : ", found '" + args[1] + "'"));
            if (!(wavelength_nm >= plenoptic::kSpectralMinNm && wavelength_nm <= plenoptic::kSpectralMaxNm))
                return fail("--wavelength " + args[1] + " is outside 380 to 720 nm, the wavelengths the glass models are checked over");
            with_wavelength = true;
            args.erase(args.begin());
        } else {
            (args[0] == "--fraction" ? with_fraction : with_blur) = true;
        }
        args.erase(args.begin());
    }
    if (args.empty())
        return fail("missing METADATA.json and points\n" + std::string(kUsage));

    const std::string path = args[0];
    const plenoptic::MetadataReading reading = plenoptic::read_metadata_file(path);
    if (!reading.ok())
        return fail(path + ": " + reading.error);
    plenoptic::RenderMetadata at_wavelength;
    if (with_wavelength) {
        at_wavelength = reading.metadata;
        at_wavelength.model = plenoptic::at_wavelength(reading.metadata.model, wavelength_nm);
    }
    const plenoptic::RenderMetadata& metadata = with_wavelength ? at_wavelength : reading.metadata;

    // The point coordinates, as text, from the command line or standard input.
    std::vector<std::string> words;
    if (args.size() == 2 && args[1] == "-") {
        std::string line;
        while (std::getline(std::cin, line)) {
            const size_t hash = line.find('#');
            if (hash != std::string::npos)
                line.erase(hash);
            for (char& c : line)
                if (c == ',' || c == '\t' || c == '\r')
                    c = ' ';
            size_t pos = 0;
            while (pos < line.size()) {
                const size_t start = line.find_first_not_of(' ', pos);
                if (start == std::string::npos)
                    break;
                const size_t stop = line.find(' ', start);
                words.push_back(line.substr(start, stop == std::string::npos ? std::string::npos : stop - start));
                pos = stop == std::string::npos ? line.size() : stop;
            }
        }
    } else {
        words.assign(args.begin() + 1, args.end());
    }
    if (words.empty())
        return fail("no points given (X Y Z after the metadata file, or '-' to read them from standard input)");
    if (words.size() % 3 != 0)
        return fail("points need three coordinates each; got " + std::to_string(words.size()) + " numbers");

    std::vector<double> values(words.size());
    for (size_t i = 0; i < words.size(); ++i)
        if (!parse_number(words[i], &values[i]))
            return fail("coordinate '" + words[i] + "' (point " + std::to_string(i / 3) + ") is not a finite number");

    for (size_t p = 0; p < values.size() / 3; ++p) {
        const plenoptic::Vec3 world{values[3 * p], values[3 * p + 1], values[3 * p + 2]};
        const std::vector<plenoptic::PixelHit> hits = plenoptic::project_world_point(metadata, world);
        const plenoptic::Vec3 optics = plenoptic::world_to_optics_mm(metadata, world).mm;
        for (const plenoptic::PixelHit& hit : hits) {
            std::printf("%zu %lld %lld %.6f %.6f", p, (long long)hit.lens.k, (long long)hit.lens.l, hit.u, hit.v);
            if (with_fraction)
                std::printf(" %.6g", hit.fraction);
            if (with_blur)
                std::printf(" %.6f", plenoptic::blur_radius_px(metadata.model, optics, hit.lens));
            std::printf("\n");
        }
    }
    return std::fflush(stdout) == 0 ? 0 : 2;
}
