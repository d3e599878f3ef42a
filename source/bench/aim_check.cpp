// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic_aim_check: whether the samples aimed where light passes (camera/aim.h) give the pixel
// values uniform samples give, in expectation (a statistical check, not a timing). It builds the
// camera as plenoptic_pass_fractions does (a real lens file, exact or --thick, the matched
// hexagonal array) and, over the pixels of a patch at the centre, an edge and a corner of the
// sensor, compares three estimates of each pixel under a made-up scene (a radiance that is a
// function of the ray leaving the camera, so no renderer is needed):
//   - reference: the plain mean of REF uniform samples (ray weight times radiance; unbiased);
//   - unaimed: shade_pixel at S samples with the aiming off (the vignetting probes' ratio);
//   - aimed: shade_pixel at S samples with the aiming on (the plain mean of weighted samples).
// The per-pixel samples are randomised quasi-Monte Carlo points (each pixel's own rotation), so
// the errors of different pixels are independent: the mean over N pixels of (estimate -
// reference) and its standard error (the spread of those differences over sqrt N) say whether an
// estimate is biased. The pixels are split into rim pixels (reference below 0.98 of the patch's
// brightest, above 0) and interior ones. Prints one JSON object.
//
//   plenoptic_aim_check --lens-file FILE --f-number N --focus-distance Z --sensor W H PIXEL_MM
//       --array-matched PITCH_MM [--thick] [--samples S] [--reference REF] [--patch P]
//       [--scene white|stripes]
//
// Scenes: white (radiance 1 everywhere: the estimate is the pixel's lit measure), stripes
// (radiance 1 + 0.8 sin(400 dx) with dx the ray's x direction: varies across a cell's rays).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/bench_camera.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/camera/pixel.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/core/sampling.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/optics.h"

namespace {

using namespace plenoptic;

struct Options {
    bench::CameraOptions camera;
    double pitch_mm = 0;
    int samples = 16, reference = 1024, patch = 48;
    bool stripes = false;
};

bool parse(int argc, char** argv, Options* o)
{
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        const int left = argc - a - 1;
        if (bench::read_camera_option(argc, argv, &a, &o->camera))
            continue;
        if (arg == "--array-matched" && left >= 1)
            o->pitch_mm = std::atof(argv[++a]);
        else if (arg == "--samples" && left >= 1)
            o->samples = std::atoi(argv[++a]);
        else if (arg == "--reference" && left >= 1)
            o->reference = std::atoi(argv[++a]);
        else if (arg == "--patch" && left >= 1)
            o->patch = std::atoi(argv[++a]);
        else if (arg == "--scene" && left >= 1) {
            const std::string s = argv[++a];
            if (s != "white" && s != "stripes")
                return false;
            o->stripes = s == "stripes";
        } else
            return false;
    }
    return o->camera.complete() && o->pitch_mm > 0 && o->samples >= 2 && o->reference >= 2 && o->patch > 0;
}

CameraParams camera(const Options& o, const Prescription& lens, double focal_mm)
{
    bench::LensFileCamera c;
    c.options = o.camera;
    c.pitch_mm = o.pitch_mm;
    c.focal_mm = c.distance_mm = focal_mm;
    c.samples = o.samples;
    return bench::camera_params(c, lens);
}

struct Stat {
    long long n = 0;
    double sum = 0, sum_sq = 0;
    void add(double x)
    {
        ++n;
        sum += x;
        sum_sq += x * x;
    }
    double mean() const { return n > 0 ? sum / n : 0; }
    double standard_error() const
    {
        if (n < 2)
            return 0;
        const double m = mean();
        return std::sqrt(std::max(0.0, (sum_sq / n - m * m) / (n - 1)));
    }
};

std::string stat_json(const Stat& s)
{
    char text[160];
    std::snprintf(text, sizeof text, "{\"pixels\": %lld, \"mean\": %.3e, \"standard_error\": %.3e}", s.n, s.mean(),
                  s.standard_error());
    return text;
}

} // namespace

int main(int argc, char** argv)
{
    Options o;
    if (!parse(argc, argv, &o)) {
        std::fprintf(stderr, "usage: plenoptic_aim_check --lens-file FILE --f-number N --focus-distance Z --sensor W H "
                             "PIXEL_MM --array-matched PITCH_MM [--thick] [--samples S] [--reference REF] [--patch P] "
                             "[--scene white|stripes]\n");
        return 2;
    }
    Prescription lens;
    if (!bench::read_lens_file("plenoptic_aim_check", o.camera.lens_file, &lens))
        return 1;
    double focal_mm;
    {
        const PlenopticCamera first = make_camera(camera(o, lens, 0));
        const double exit_pupil_z = first.lens_length_mm() - first.paraxial().exit_pupil_z;
        focal_mm = o.pitch_mm * (exit_pupil_z + first.distance_mm) / first.paraxial().exit_pupil_mm;
    }
    const CameraParams params = camera(o, lens, focal_mm);
    const std::string error = check_camera(params);
    if (!error.empty()) {
        std::fprintf(stderr, "plenoptic_aim_check: %s\n", error.c_str());
        return 1;
    }
    const PlenopticCamera aimed = with_film(make_camera(params), o.camera.width, o.camera.height);
    PlenopticCamera unaimed = aimed;
    unaimed.sampling.aim = false;
    const bool stripes = o.stripes;
    auto radiance = [stripes](const OpticsRay& ray) {
        if (!stripes)
            return 1.0;
        const double norm = std::sqrt(ray.dir.x * ray.dir.x + ray.dir.y * ray.dir.y + ray.dir.z * ray.dir.z);
        return 1 + 0.8 * std::sin(400 * ray.dir.x / norm);
    };
    auto trace = [&radiance](const OpticsRay& ray) {
        const double v = radiance(ray);
        return Rgbt{v, v, v, 0};
    };
    const int W = o.camera.width, H = o.camera.height, side = std::min(o.patch, std::min(W, H));
    struct Place {
        const char* name;
        int i0, j0;
    };
    const Place places[] = {{"centre", W / 2 - side / 2, H / 2 - side / 2},
                            {"edge", W - side, H / 2 - side / 2},
                            {"corner", W - side, H - side}};
    std::printf("{\"lens_file\": \"%s\", \"thick_lens\": %s, \"scene\": \"%s\", \"samples\": %d, \"reference\": %d, "
                "\"patch\": %d, \"aiming\": %s,\n \"places\": [\n",
                o.camera.lens_file.c_str(), o.camera.thick ? "true" : "false", stripes ? "stripes" : "white", o.samples, o.reference,
                side, aimed.sampling.aim ? "true" : "false");
    for (int k = 0; k < 3; ++k) {
        const Place& p = places[k];
        std::vector<double> reference, old_value, new_value;
        double brightest = 0;
        for (int j = p.j0; j < p.j0 + side; ++j)
            for (int i = p.i0; i < p.i0 + side; ++i) {
                double sum = 0;
                for (int n = 0; n < o.reference; ++n) {
                    const OpticsRay ray = unaimed.generate_ray(i, j, make_sample(i, j, n, o.reference));
                    if (ray.passed)
                        sum += ray.weight * radiance(ray);
                }
                reference.push_back(sum / o.reference);
                brightest = std::max(brightest, reference.back());
                old_value.push_back(shade_pixel(unaimed, i, j, trace).r);
                new_value.push_back(shade_pixel(aimed, i, j, trace).r);
            }
        Stat old_rim, new_rim, old_inside, new_inside, old_all, new_all, paired;
        for (size_t n = 0; n < reference.size(); ++n) {
            const double r = reference[n];
            const bool dark = !(r > 0) && old_value[n] == 0 && new_value[n] == 0;
            if (dark)
                continue;
            const bool rim = r < 0.98 * brightest;
            (rim ? old_rim : old_inside).add(old_value[n] - r);
            (rim ? new_rim : new_inside).add(new_value[n] - r);
            old_all.add(old_value[n] - r);
            new_all.add(new_value[n] - r);
            paired.add(new_value[n] - old_value[n]);
        }
        std::printf("  {\"place\": \"%s\", \"first_pixel\": [%d, %d], \"brightest\": %.6f,\n", p.name, p.i0, p.j0,
                    brightest);
        std::printf("   \"unaimed_minus_reference\": {\"all\": %s, \"rim\": %s, \"inside\": %s},\n",
                    stat_json(old_all).c_str(), stat_json(old_rim).c_str(), stat_json(old_inside).c_str());
        std::printf("   \"aimed_minus_reference\": {\"all\": %s, \"rim\": %s, \"inside\": %s},\n",
                    stat_json(new_all).c_str(), stat_json(new_rim).c_str(), stat_json(new_inside).c_str());
        std::printf("   \"aimed_minus_unaimed\": %s}%s\n", stat_json(paired).c_str(), k < 2 ? "," : "");
    }
    std::printf(" ]}\n");
    return 0;
}
