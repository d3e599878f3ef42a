// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic_microimage_truth: the microimage truth stage alone (truth/microimages.h), timed, for
// BENCHMARKS.md ("Microimage truth"). It builds the camera a scene with these keywords would give
// (main_lens { lens_file f_number focus_distance }, a hexagonal array of thin microlenses,
// sensor { pixel_size offset }), runs microimage_truth on the W x H picture, and prints one JSON
// object (lenses, wall and CPU seconds of the stage, peak RSS of the process). With --csv it also
// writes the microimages CSV as the render would (the lattice fit's residuals included).
//
//   plenoptic_microimage_truth --lens-file FILE --f-number N --focus-distance Z
//       --sensor W H PIXEL_MM --array PITCH_MM F_MM D_MM [--offset X_MM Y_MM] [--threads T]
//       [--errors S F R SEED] [--refracting R CAP SUBSTRATE IOR] [--reference] [--csv OUT]
//
// --offset shifts the sensor (sensor { offset }): a crop of a larger raw away from its centre,
// e.g. its corner. --errors gives the array manufacturing errors (errors { position S focal_length F
// rotation R seed SEED }). --reference measures every lens from scratch (reuse_neighbours false: the
// integration as it was before the neighbours' radii were reused). --refracting replaces the thin
// microlenses by plano-convex caps (lens { surface { radius R } thickness CAP ior IOR substrate
// SUBSTRATE }, the curved side towards the scene; F_MM of --array is then unused).

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/resource.h>

#include "plenoptic/camera/params.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/optics.h"
#include "plenoptic/truth/microimages.h"

namespace {

using namespace plenoptic;

struct Options {
    std::string lens_file;
    double f_number = 0;
    double focus_distance = 0;
    int width = 0, height = 0;
    double pixel_mm = 0;
    double pitch_mm = 0, focal_mm = 0, distance_mm = 0;
    double offset_mm[2] = {0, 0};
    int threads = 0;
    bool errors = false;
    bool reference = false;
    bool refracting = false;
    double refracting_values[4] = {0, 0, 0, 0};  // radius, cap, substrate, ior
    double error_values[3] = {0, 0, 0};
    long long seed = 0;
    std::string csv;
};

bool parse(int argc, char** argv, Options* o)
{
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        const int left = argc - a - 1;
        if (arg == "--lens-file" && left >= 1)
            o->lens_file = argv[++a];
        else if (arg == "--f-number" && left >= 1)
            o->f_number = std::atof(argv[++a]);
        else if (arg == "--focus-distance" && left >= 1)
            o->focus_distance = std::atof(argv[++a]);
        else if (arg == "--sensor" && left >= 3) {
            o->width = std::atoi(argv[++a]);
            o->height = std::atoi(argv[++a]);
            o->pixel_mm = std::atof(argv[++a]);
        } else if (arg == "--array" && left >= 3) {
            o->pitch_mm = std::atof(argv[++a]);
            o->focal_mm = std::atof(argv[++a]);
            o->distance_mm = std::atof(argv[++a]);
        } else if (arg == "--offset" && left >= 2) {
            o->offset_mm[0] = std::atof(argv[++a]);
            o->offset_mm[1] = std::atof(argv[++a]);
        } else if (arg == "--threads" && left >= 1)
            o->threads = std::atoi(argv[++a]);
        else if (arg == "--errors" && left >= 4) {
            o->errors = true;
            for (double& value : o->error_values)
                value = std::atof(argv[++a]);
            o->seed = std::atoll(argv[++a]);
        } else if (arg == "--refracting" && left >= 4) {
            o->refracting = true;
            for (double& value : o->refracting_values)
                value = std::atof(argv[++a]);
        } else if (arg == "--reference")
            o->reference = true;
        else if (arg == "--csv" && left >= 1)
            o->csv = argv[++a];
        else
            return false;
    }
    return !o->lens_file.empty() && o->f_number > 0 && o->focus_distance > 0 && o->width > 0 && o->height > 0 &&
           o->pixel_mm > 0 && o->pitch_mm > 0 && o->focal_mm > 0 && o->distance_mm > 0 && o->threads >= 0;
}

double cpu_seconds()
{
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_utime.tv_sec + 1e-6 * usage.ru_utime.tv_usec + usage.ru_stime.tv_sec +
           1e-6 * usage.ru_stime.tv_usec;
}

} // namespace

int main(int argc, char** argv)
{
    Options o;
    if (!parse(argc, argv, &o)) {
        std::fprintf(stderr, "usage: plenoptic_microimage_truth --lens-file FILE --f-number N --focus-distance Z\n"
                             "         --sensor W H PIXEL_MM --array PITCH_MM F_MM D_MM [--offset X_MM Y_MM]\n"
                             "         [--threads T] [--errors S F R SEED] [--refracting R CAP SUBSTRATE IOR]\n"
                             "         [--reference] [--csv OUT]\n");
        return 2;
    }
    std::ifstream file(o.lens_file);
    if (!file) {
        std::fprintf(stderr, "plenoptic_microimage_truth: cannot read %s\n", o.lens_file.c_str());
        return 1;
    }
    std::stringstream text;
    text << file.rdbuf();
    const ParsedPrescription parsed = parse_lens_file(text.str());
    if (parsed.error.any()) {
        std::fprintf(stderr, "plenoptic_microimage_truth: %s, line %d: %s\n", o.lens_file.c_str(), parsed.error.line,
                     parsed.error.message.c_str());
        return 1;
    }
    CameraParams p;
    p.main.given = true;
    p.main.type = MainLensType::Prescription;
    p.main.has_prescription = true;
    p.main.prescription = parsed.prescription;
    p.main.lens_file = o.lens_file;
    p.main.has_f_number = true;
    p.main.f_number = o.f_number;
    p.main.has_focus_distance = true;
    p.main.focus_distance_units = o.focus_distance;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = o.pixel_mm;
    p.sensor.offset_mm[0] = o.offset_mm[0];
    p.sensor.offset_mm[1] = o.offset_mm[1];
    p.array.given = true;
    p.array.grid = GridType::Hexagonal;
    p.array.has_pitch = true;
    p.array.pitch_mm = o.pitch_mm;
    p.array.has_lens = true;
    p.array.lens = MicrolensType::ThinLens;
    p.array.focal_length_count = 1;
    p.array.focal_lengths_mm[0] = o.focal_mm;
    if (o.refracting) {
        p.array.lens = MicrolensType::Refracting;
        p.array.focal_length_count = 0;
        p.array.refracting.radius_mm = o.refracting_values[0];
        p.array.refracting.cap_mm = o.refracting_values[1];
        p.array.refracting.substrate_mm = o.refracting_values[2];
        p.array.refracting.ior = o.refracting_values[3];
        p.array.refracting.curved_towards_scene = true;
    }
    p.array.has_distance = true;
    p.array.distance_mm = o.distance_mm;
    if (o.errors) {
        p.array.has_errors = true;
        p.array.errors.position_sd_mm = o.error_values[0];
        p.array.errors.focal_sd = o.error_values[1];
        p.array.errors.rotation_deg = o.error_values[2];
        p.array.errors.seed = o.seed;
    }
    const std::string error = check_camera(p);
    if (!error.empty()) {
        std::fprintf(stderr, "plenoptic_microimage_truth: %s\n", error.c_str());
        return 1;
    }
    const PlenopticCamera m = with_film(make_camera(p), o.width, o.height);
    MicroimageOptions options = default_microimage_options();
    options.threads = o.threads;
    options.reuse_neighbours = !o.reference;

    const double cpu0 = cpu_seconds();
    const auto wall0 = std::chrono::steady_clock::now();
    const std::vector<MicroimageTruth> truth = microimage_truth(m, options);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    const double cpu = cpu_seconds() - cpu0;
    std::size_t lit = 0;
    for (const MicroimageTruth& t : truth)
        lit += t.lit ? 1 : 0;
    if (!o.csv.empty()) {
        const LatticeFit fit = fit_microimage_lattice(m, truth);
        std::ofstream out(o.csv);
        out << microimages_csv(m, truth, fit);
        if (!out) {
            std::fprintf(stderr, "plenoptic_microimage_truth: cannot write %s\n", o.csv.c_str());
            return 1;
        }
    }
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    std::printf("{\"size\": [%d, %d], \"offset_mm\": [%.9g, %.9g], \"lenses\": %zu, \"lit_lenses\": %zu, "
                "\"threads\": %d, \"wall_s\": %.3f, \"cpu_s\": %.3f, \"peak_rss_mib\": %.1f}\n",
                o.width, o.height, o.offset_mm[0], o.offset_mm[1], truth.size(), lit, o.threads, wall, cpu,
                usage.ru_maxrss / 1024.0);
    return 0;
}
