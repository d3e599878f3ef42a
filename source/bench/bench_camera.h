// SPDX-License-Identifier: AGPL-3.0-or-later
// The camera the bench programs build, as a scene with these keywords would give it:
//   main_lens { lens_file "<file>" [thick_lens] f_number N focus_distance Z }
//   [microlens_array { hexagonal pitch P focal_length F distance D }]
//   sensor { pixel_size S }  samples n
// (one place, so the bench programs measure the same camera the parser would make).

#ifndef PLENOPTIC_BENCH_CAMERA_H
#define PLENOPTIC_BENCH_CAMERA_H

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "plenoptic/camera/params.h"
#include "plenoptic/lens/prescription.h"

namespace plenoptic {
namespace bench {

// What the bench programs' shared options say: --lens-file FILE --f-number N --focus-distance Z
// --sensor W H PIXEL_MM [--thick].
struct CameraOptions {
    std::string lens_file;
    bool thick = false;  // thick_lens: the prescription's paraxial equivalent, not traced
    double f_number = 0, focus_distance = 0;
    int width = 0, height = 0;
    double pixel_mm = 0;

    // Every option given, with a value in range.
    bool complete() const
    {
        return !lens_file.empty() && f_number > 0 && focus_distance > 0 && width > 0 && height > 0 && pixel_mm > 0;
    }
};

// When argv[*a] is one of the shared options with its values after it: reads them into *o, leaves
// *a at the last of them and returns true; else false (*a and *o unchanged).
inline bool read_camera_option(int argc, char** argv, int* a, CameraOptions* o)
{
    const std::string arg = argv[*a];
    const int left = argc - *a - 1;
    if (arg == "--lens-file" && left >= 1)
        o->lens_file = argv[++*a];
    else if (arg == "--f-number" && left >= 1)
        o->f_number = std::atof(argv[++*a]);
    else if (arg == "--focus-distance" && left >= 1)
        o->focus_distance = std::atof(argv[++*a]);
    else if (arg == "--sensor" && left >= 3) {
        o->width = std::atoi(argv[++*a]);
        o->height = std::atoi(argv[++*a]);
        o->pixel_mm = std::atof(argv[++*a]);
    } else if (arg == "--thick")
        o->thick = true;
    else
        return false;
    return true;
}

// The prescription of `path` (a lens file) into *lens; false, with "<program>: <what went wrong>"
// on stderr, when it cannot be read or parsed.
inline bool read_lens_file(const char* program, const std::string& path, Prescription* lens)
{
    std::ifstream file(path);
    if (!file) {
        std::fprintf(stderr, "%s: cannot read %s\n", program, path.c_str());
        return false;
    }
    std::stringstream text;
    text << file.rdbuf();
    const ParsedPrescription parsed = parse_lens_file(text.str());
    if (parsed.error.any()) {
        std::fprintf(stderr, "%s: %s, line %d: %s\n", program, path.c_str(), parsed.error.line, parsed.error.message.c_str());
        return false;
    }
    *lens = parsed.prescription;
    return true;
}

struct LensFileCamera {
    CameraOptions options;
    double pitch_mm = 0, focal_mm = 0, distance_mm = 0;  // focal_mm 0: no array
    int samples = 1;
};

// --refracting R CAP SUBSTRATE IOR [--caps-to-sensor]: the array's lenses as plano-convex caps
// (microlens_array { lens { surface { radius R } thickness CAP ior IOR substrate SUBSTRATE } }),
// the curved side towards the scene unless caps_to_sensor.
struct RefractingOption {
    bool given = false;
    double radius_mm = 0, cap_mm = 0, substrate_mm = 0, ior = 0;
    bool caps_to_sensor = false;
};

// As read_camera_option, for --refracting and --caps-to-sensor.
inline bool read_refracting_option(int argc, char** argv, int* a, RefractingOption* o)
{
    const std::string arg = argv[*a];
    const int left = argc - *a - 1;
    if (arg == "--refracting" && left >= 4) {
        o->given = true;
        o->radius_mm = std::atof(argv[++*a]);
        o->cap_mm = std::atof(argv[++*a]);
        o->substrate_mm = std::atof(argv[++*a]);
        o->ior = std::atof(argv[++*a]);
    } else if (arg == "--caps-to-sensor")
        o->caps_to_sensor = true;
    else
        return false;
    return true;
}

// --errors S F R SEED: the array's manufacturing errors (microlens_array { errors { position S
// focal_length F rotation R seed SEED } }).
struct ErrorsOption {
    bool given = false;
    double position_sd_mm = 0, focal_sd = 0, rotation_deg = 0;
    long long seed = 0;
};

// As read_camera_option, for --errors.
inline bool read_errors_option(int argc, char** argv, int* a, ErrorsOption* o)
{
    if (!(std::string(argv[*a]) == "--errors" && argc - *a - 1 >= 4))
        return false;
    o->given = true;
    o->position_sd_mm = std::atof(argv[++*a]);
    o->focal_sd = std::atof(argv[++*a]);
    o->rotation_deg = std::atof(argv[++*a]);
    o->seed = std::atoll(argv[++*a]);
    return true;
}

// The array of *p (an array given) with those errors, when given.
inline void use_errors(const ErrorsOption& e, CameraParams* p)
{
    if (!e.given)
        return;
    p->array.has_errors = true;
    p->array.errors.position_sd_mm = e.position_sd_mm;
    p->array.errors.focal_sd = e.focal_sd;
    p->array.errors.rotation_deg = e.rotation_deg;
    p->array.errors.seed = e.seed;
}

inline CameraParams camera_params(const LensFileCamera& camera, const Prescription& lens)
{
    const CameraOptions& c = camera.options;
    CameraParams p;
    p.main.given = true;
    p.main.type = c.thick ? MainLensType::ThickLens : MainLensType::Prescription;
    p.main.has_prescription = true;
    p.main.prescription = lens;
    p.main.lens_file = c.lens_file;
    p.main.has_f_number = true;
    p.main.f_number = c.f_number;
    p.main.has_focus_distance = true;
    p.main.focus_distance_units = c.focus_distance;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = c.pixel_mm;
    if (camera.focal_mm > 0) {
        p.array.given = true;
        p.array.grid = GridType::Hexagonal;
        p.array.has_pitch = true;
        p.array.pitch_mm = camera.pitch_mm;
        p.array.has_lens = true;
        p.array.lens = MicrolensType::ThinLens;
        p.array.focal_length_count = 1;
        p.array.focal_lengths_mm[0] = camera.focal_mm;
        p.array.has_distance = true;
        p.array.distance_mm = camera.distance_mm;
    }
    p.sampling.samples = camera.samples;
    return p;
}

// The array of *p (an array given) with refracting caps instead of its thin lenses, when given.
inline void use_refracting(const RefractingOption& r, CameraParams* p)
{
    if (!r.given)
        return;
    p->array.lens = MicrolensType::Refracting;
    p->array.focal_length_count = 0;
    p->array.refracting.radius_mm = r.radius_mm;
    p->array.refracting.cap_mm = r.cap_mm;
    p->array.refracting.substrate_mm = r.substrate_mm;
    p->array.refracting.ior = r.ior;
    p->array.refracting.curved_towards_scene = !r.caps_to_sensor;
}

} // namespace bench
} // namespace plenoptic

#endif
