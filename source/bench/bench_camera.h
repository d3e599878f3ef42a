// SPDX-License-Identifier: AGPL-3.0-or-later
// The camera the bench programs build, as a scene with these keywords would give it:
//   main_lens { lens_file "<file>" [thick_lens] f_number N focus_distance Z }
//   [microlens_array { hexagonal pitch P focal_length F distance D }]
//   sensor { pixel_size S }  samples n
// (one place, so the bench programs measure the same camera the parser would make).

#ifndef PLENOPTIC_BENCH_CAMERA_H
#define PLENOPTIC_BENCH_CAMERA_H

#include <string>

#include "plenoptic/camera/params.h"
#include "plenoptic/lens/prescription.h"

namespace plenoptic {
namespace bench {

struct LensFileCamera {
    std::string lens_file;
    bool thick = false;  // thick_lens: the prescription's paraxial equivalent, not traced
    double f_number = 0, focus_distance = 0, pixel_mm = 0;
    double pitch_mm = 0, focal_mm = 0, distance_mm = 0;  // focal_mm 0: no array
    int samples = 1;
};

inline CameraParams camera_params(const LensFileCamera& c, const Prescription& lens)
{
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
    if (c.focal_mm > 0) {
        p.array.given = true;
        p.array.grid = GridType::Hexagonal;
        p.array.has_pitch = true;
        p.array.pitch_mm = c.pitch_mm;
        p.array.has_lens = true;
        p.array.lens = MicrolensType::ThinLens;
        p.array.focal_length_count = 1;
        p.array.focal_lengths_mm[0] = c.focal_mm;
        p.array.has_distance = true;
        p.array.distance_mm = c.distance_mm;
    }
    p.sampling.samples = c.samples;
    return p;
}

} // namespace bench
} // namespace plenoptic

#endif
