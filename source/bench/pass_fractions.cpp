// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic_pass_fractions: how many of the camera rays generated behind a real main lens pass it
// (a benchmark figure). A count, not a timing: it builds the camera's PlenopticCamera from
// parameters as the scene parser would (check_camera, make_camera), asks generate_ray for the
// camera's own samples (make_sample, as shade_pixel does) of the central, an edge and a corner
// pixel and of a patch of pixels around each, and counts the rays that pass the lens. Without an
// array it also counts what sampling the whole rear element's clear aperture uniformly (pbrt's
// RealisticCamera before its exit-pupil bounds) would pass, so that the waste with and without
// the pupil bounds (lens/pupil_bounds.h) can be compared. Run by `tools/bench --only
// real_lens`; BENCHMARKS.md has the figures. Prints one JSON object on stdout.
//
//   plenoptic_pass_fractions --lens-file FILE --f-number N --focus-distance Z
//       --sensor W H PIXEL_MM [--array-matched PITCH_MM | --array PITCH_MM F_MM D_MM] [--thick]
//       [--samples S] [--patch P] [--unaimed] [--lit-patch L] [--refracting R CAP SUBSTRATE IOR]
//       [--errors S F R SEED]
//
// --array-matched puts a hexagonal plenoptic 1.0 array at the focused image: thin microlenses of
// focal length f = PITCH * the lens's working f-number (exit pupil to array over its diameter),
// the sensor at f behind them (f-number matching); --array gives a hexagonal array's pitch, microlens
// focal length and array-sensor distance d directly. --thick uses the lens's paraxial equivalent
// (thick_lens) instead of the exact trace. --samples: samples per pixel (the make_sample count;
// default 256); --patch: the side of the pixel patches (default 16, or two microlens pitches).
// Besides the three places, a profile: patches along the centre row from the axis to the edge.
// --unaimed samples every pixel and cell uniformly (the camera's sampling.aim off: how samples
// were spread before they were aimed where light passes, camera/aim.h). --lit-patch L adds, per
// place, the counts over the lit pixels of an L x L patch there (a pixel is lit when any of the
// points the uniform sampling looks at passes: pixel_receives_light with the aiming off), with the
// smallest pass fraction of a lit pixel, the 5th percentile, and how many lit pixels pass 95 %.
// --refracting makes the array's lenses plano-convex caps (microlens_array { lens { surface { radius R }
// thickness CAP ior IOR substrate SUBSTRATE } }, curved side to the scene; with --array, whose F_MM is
// then unused), which do not aim: their samples are spread uniformly over the pixel and the cell.
// --errors gives the array manufacturing errors (errors { position S focal_length F rotation R seed SEED }).
// light_field_radius_mm is where the pupil bounds find that no light passes any more (-1 for the
// thick lens, which has no such bounds; the bounds with an array are for points of its plane).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bench/bench_camera.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/optics.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/core/sampling.h"
#include "plenoptic/camera/pixel.h"

namespace {

using namespace plenoptic;

struct Options {
    bench::CameraOptions camera;
    double array_pitch_mm = 0;  // 0: no array
    double array_focal_mm = 0;  // given with --array; 0 with --array-matched (computed)
    double array_distance_mm = 0;
    int samples = 256;
    int patch = 0;
    bool unaimed = false;
    int lit_patch = 0;
    bench::RefractingOption refracting;
    bench::ErrorsOption errors;
};

void usage()
{
    std::fprintf(stderr,
                 "usage: plenoptic_pass_fractions --lens-file FILE --f-number N --focus-distance Z\n"
                 "         --sensor W H PIXEL_MM [--array-matched PITCH_MM | --array PITCH_MM F_MM D_MM] [--thick]\n"
                 "         [--samples S] [--patch P] [--unaimed] [--lit-patch L] [--refracting R CAP SUBSTRATE IOR]\n"
                 "         [--errors S F R SEED]\n");
}

bool parse(int argc, char** argv, Options* o)
{
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        const int left = argc - a - 1;
        if (bench::read_camera_option(argc, argv, &a, &o->camera) ||
            bench::read_refracting_option(argc, argv, &a, &o->refracting) ||
            bench::read_errors_option(argc, argv, &a, &o->errors))
            continue;
        if (arg == "--array-matched" && left >= 1)
            o->array_pitch_mm = std::atof(argv[++a]);
        else if (arg == "--array" && left >= 3) {
            o->array_pitch_mm = std::atof(argv[++a]);
            o->array_focal_mm = std::atof(argv[++a]);
            o->array_distance_mm = std::atof(argv[++a]);
        } else if (arg == "--samples" && left >= 1)
            o->samples = std::atoi(argv[++a]);
        else if (arg == "--patch" && left >= 1)
            o->patch = std::atoi(argv[++a]);
        else if (arg == "--unaimed")
            o->unaimed = true;
        else if (arg == "--lit-patch" && left >= 1)
            o->lit_patch = std::atoi(argv[++a]);
        else
            return false;
    }
    if (o->array_focal_mm > 0 && !(o->array_distance_mm > 0))
        return false;
    if (o->refracting.given && !(o->array_focal_mm > 0))
        return false;  // the caps need --array's distance
    return o->camera.complete() && o->samples >= 2 && o->patch >= 0 && o->lit_patch >= 0 && o->array_pitch_mm >= 0;
}

// The camera a scene with these keywords would give (main_lens { lens_file f_number
// focus_distance [thick_lens] }, sensor { pixel_size }, optionally the matched array).
CameraParams camera(const Options& o, const Prescription& lens, double array_focal_mm, double array_distance_mm)
{
    bench::LensFileCamera c;
    c.options = o.camera;
    c.pitch_mm = o.array_pitch_mm;
    c.focal_mm = array_focal_mm;
    c.distance_mm = array_distance_mm;
    c.samples = o.samples;
    CameraParams p = bench::camera_params(c, lens);
    if (array_focal_mm > 0) {
        bench::use_refracting(o.refracting, &p);
        bench::use_errors(o.errors, &p);
    }
    return p;
}

// Image-side f-number: exit pupil to the plane D behind the rear vertex, over the pupil's diameter
// (the metadata's paraxial.working_f_number).
double working_f_number(const PlenopticCamera& m)
{
    const double exit_pupil_z = m.lens_length_mm() - m.paraxial().exit_pupil_z;  // optics frame
    return (exit_pupil_z + m.distance_mm) / m.paraxial().exit_pupil_mm;
}

struct Count {
    long long generated = 0;
    long long passed = 0;
    long long unbounded_generated = 0;  // without an array: the rear element sampled uniformly
    long long unbounded_passed = 0;
};

// The samples of pixel (i, j) as shade_pixel makes them (fixed count, own lens): sample n of
// `samples` from make_sample, then generate_ray. Without an array also the pbrt-style sample: the
// same aperture sample mapped onto the rear element's clear aperture (a disc in the plane of the
// rear vertex), traced with the lens's own exact trace.
void count_pixel(const PlenopticCamera& m, int i, int j, int samples, double rear_radius_mm, Count* c)
{
    for (int n = 0; n < samples; ++n) {
        const CameraSample s = make_sample(i, j, n, samples);
        ++c->generated;
        const OpticsRay ray = m.generate_ray(i, j, s);
        if (ray.passed)
            ++c->passed;
        if (m.array.grid == GridType::None && rear_radius_mm > 0) {
            const Vec3 p = m.sensor.point(i + s.pixel_u, j + s.pixel_v);
            const Vec2 d = concentric_disc(s.lens_u, s.lens_v);
            const Vec3 on_rear{rear_radius_mm * d.x, rear_radius_mm * d.y, 0};
            ++c->unbounded_generated;
            if (m.lens->to_scene(p, on_rear - p, true).passed)
                ++c->unbounded_passed;
        }
    }
}

// Over the lit pixels of the patch of side `side` from (i0, j0): their samples and how many pass,
// and the spread of the pixels' own pass fractions.
std::string lit_counts_json(const PlenopticCamera& m, const PlenopticCamera& uniform, int i0, int j0, int side, int samples)
{
    long long generated = 0, passed = 0;
    std::vector<double> fractions;
    for (int j = j0; j < j0 + side; ++j)
        for (int i = i0; i < i0 + side; ++i) {
            if (!pixel_receives_light(uniform, i, j))
                continue;
            int pass = 0;
            for (int n = 0; n < samples; ++n)
                if (m.generate_ray(i, j, make_sample(i, j, n, samples)).passed)
                    ++pass;
            generated += samples;
            passed += pass;
            fractions.push_back(double(pass) / samples);
        }
    std::sort(fractions.begin(), fractions.end());
    int at_least_95 = 0;
    for (double f : fractions)
        at_least_95 += f >= 0.95 ? 1 : 0;
    char text[256];
    std::snprintf(text, sizeof text,
                  "{\"lit_pixels\": %d, \"generated\": %lld, \"passed\": %lld, \"pass_fraction\": %.6f, "
                  "\"smallest_pixel_fraction\": %.6f, \"pixel_fraction_5th_percentile\": %.6f, \"pixels_at_least_95\": %d}",
                  int(fractions.size()), generated, passed, generated > 0 ? double(passed) / double(generated) : 0.0,
                  fractions.empty() ? 0.0 : fractions.front(),
                  fractions.empty() ? 0.0 : fractions[fractions.size() / 20], at_least_95);
    return text;
}

std::string fraction(long long part, long long whole)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.6f", whole > 0 ? double(part) / double(whole) : 0.0);
    return text;
}

std::string counts_json(const Count& c, bool unbounded)
{
    std::ostringstream out;
    out << "{\"generated\": " << c.generated << ", \"passed\": " << c.passed
        << ", \"pass_fraction\": " << fraction(c.passed, c.generated);
    if (unbounded)
        out << ", \"unbounded_generated\": " << c.unbounded_generated << ", \"unbounded_passed\": "
            << c.unbounded_passed << ", \"unbounded_pass_fraction\": "
            << fraction(c.unbounded_passed, c.unbounded_generated);
    out << "}";
    return out.str();
}

} // namespace

int main(int argc, char** argv)
{
    Options o;
    if (!parse(argc, argv, &o)) {
        usage();
        return 2;
    }
    Prescription lens;
    if (!bench::read_lens_file("plenoptic_pass_fractions", o.camera.lens_file, &lens))
        return 1;

    // The array's focal length depends on D, which the model computes: a first model without it.
    double array_focal_mm = 0;
    double working_n = 0;
    {
        const CameraParams first = camera(o, lens, 0, 0);
        const std::string error = check_camera(first);
        if (!error.empty()) {
            std::fprintf(stderr, "plenoptic_pass_fractions: %s\n", error.c_str());
            return 1;
        }
        const PlenopticCamera m = make_camera(first);
        working_n = working_f_number(m);
        if (o.array_pitch_mm > 0)
            array_focal_mm = o.array_focal_mm > 0 ? o.array_focal_mm : o.array_pitch_mm * working_n;
    }
    const double array_distance_mm = o.array_focal_mm > 0 ? o.array_distance_mm : array_focal_mm;
    const CameraParams params = camera(o, lens, array_focal_mm, array_distance_mm);
    const std::string error = check_camera(params);
    if (!error.empty()) {
        std::fprintf(stderr, "plenoptic_pass_fractions: %s\n", error.c_str());
        return 1;
    }
    PlenopticCamera m = with_film(make_camera(params), o.camera.width, o.camera.height);
    PlenopticCamera uniform = m;
    uniform.sampling.aim = false;
    if (o.unaimed)
        m.sampling.aim = false;
    const int W = o.camera.width, H = o.camera.height;
    int patch = o.patch;
    if (patch == 0)
        patch = o.array_pitch_mm > 0 ? int(std::ceil(2 * o.array_pitch_mm / o.camera.pixel_mm)) : 16;
    patch = std::min(patch, std::min(W, H));
    const double rear_radius = 0.5 * m.prescription().surfaces.back().aperture_mm;
    const bool unbounded = m.array.grid == GridType::None && m.lens && m.lens->traced();

    struct Place {
        const char* name;
        int i, j;    // the pixel
        int i0, j0;  // the patch's first pixel
    };
    const Place places[] = {
        {"centre", W / 2, H / 2, W / 2 - patch / 2, H / 2 - patch / 2},
        {"edge", W - 1, H / 2, W - patch, H / 2 - patch / 2},
        {"corner", W - 1, H - 1, W - patch, H - patch},
    };

    std::printf("{\n \"lens_file\": \"%s\", \"thick_lens\": %s, \"f_number\": %.9g, \"focus_distance\": %.9g,\n",
                o.camera.lens_file.c_str(), o.camera.thick ? "true" : "false", m.f_number(), o.camera.focus_distance);
    std::printf(" \"effective_focal_length_mm\": %.9g, \"distance_mm\": %.9g, \"working_f_number\": %.9g,\n",
                m.focal_length_mm(), m.distance_mm, working_n);
    std::printf(" \"exit_pupil_radius_mm\": %.9g, \"rear_aperture_radius_mm\": %.9g, \"light_field_radius_mm\": %.9g,\n",
                m.lens->exit_pupil_radius(), rear_radius, m.pupil_bounds ? m.pupil_bounds->field_radius_mm() : -1.0);
    if (m.array.grid != GridType::None)
        std::printf(" \"array\": {\"grid\": \"hexagonal\", \"pitch_mm\": %.9g, \"focal_length_mm\": %.9g, "
                    "\"distance_mm\": %.9g},\n", m.array.pitch_mm, m.array.focal_length_mm(LensIndex{0, 0}), m.array.distance_mm);
    else
        std::printf(" \"array\": null,\n");
    std::printf(" \"sensor\": {\"width\": %d, \"height\": %d, \"pixel_size_mm\": %.9g}, \"samples\": %d, "
                "\"patch\": %d, \"aimed\": %s,\n \"places\": [\n", W, H, o.camera.pixel_mm, o.samples, patch,
                m.sampling.aim ? "true" : "false");
    for (int k = 0; k < 3; ++k) {
        const Place& p = places[k];
        Count pixel, block;
        count_pixel(m, p.i, p.j, o.samples, unbounded ? rear_radius : 0, &pixel);
        for (int j = p.j0; j < p.j0 + patch; ++j)
            for (int i = p.i0; i < p.i0 + patch; ++i)
                count_pixel(m, i, j, o.samples, unbounded ? rear_radius : 0, &block);
        const Vec3 at = m.sensor.point(p.i + 0.5, p.j + 0.5);
        std::printf("  {\"place\": \"%s\", \"pixel\": [%d, %d], \"field_radius_mm\": %.6f,\n", p.name, p.i, p.j,
                    std::hypot(at.x, at.y));
        std::printf("   \"pixel_counts\": %s,\n", counts_json(pixel, unbounded).c_str());
        std::printf("   \"patch_first_pixel\": [%d, %d], \"patch_counts\": %s", p.i0, p.j0,
                    counts_json(block, unbounded).c_str());
        if (o.lit_patch > 0) {
            // The lit-pixel patch at the same place, inside the picture.
            const int side = std::min(o.lit_patch, std::min(W, H));
            const int li = std::max(0, std::min(W - side, p.i - side / 2)), lj = std::max(0, std::min(H - side, p.j - side / 2));
            std::printf(",\n   \"lit_patch_first_pixel\": [%d, %d], \"lit_patch\": %d, \"lit_counts\": %s", li, lj,
                        side, lit_counts_json(m, uniform, li, lj, side, o.samples).c_str());
        }
        std::printf("}%s\n", k < 2 ? "," : "");
    }
    std::printf(" ],\n");
    // Along the centre row from the axis to the right edge: patches at kProfile field radii.
    const int kProfile = 12;
    std::printf(" \"profile\": [\n");
    for (int k = 0; k <= kProfile; ++k) {
        const int i0 = W / 2 - patch / 2 + int(std::lround(double(k) / kProfile * (W - W / 2 - (patch - patch / 2))));
        const int j0 = H / 2 - patch / 2;
        Count block;
        for (int j = j0; j < j0 + patch; ++j)
            for (int i = i0; i < i0 + patch; ++i)
                count_pixel(m, i, j, o.samples, unbounded ? rear_radius : 0, &block);
        const Vec3 at = m.sensor.point(i0 + 0.5 * patch, j0 + 0.5 * patch);
        std::printf("  {\"patch_first_pixel\": [%d, %d], \"field_radius_mm\": %.6f, \"patch_counts\": %s}%s\n", i0, j0,
                    std::hypot(at.x, at.y), counts_json(block, unbounded).c_str(), k < kProfile ? "," : "");
    }
    std::printf(" ]\n}\n");
    return 0;
}
