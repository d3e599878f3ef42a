// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic_microimage_truth: the microimage truth stage alone (truth/microimages.h), timed, for
// BENCHMARKS.md ("Microimage truth"). It builds the camera a scene with these keywords would give
// (main_lens { lens_file f_number focus_distance }, a hexagonal array of thin microlenses,
// sensor { pixel_size offset }), runs microimage_truth on the W x H picture, and prints one JSON
// object (lenses, wall and CPU seconds of the stage, peak RSS of the process). With --csv it also
// writes the microimages CSV as the render would (the lattice fit's residuals included).
//
//   plenoptic_microimage_truth --lens-file FILE --f-number N --focus-distance Z
//       --sensor W H PIXEL_MM --array PITCH_MM F_MM D_MM [--thick] [--offset X_MM Y_MM] [--threads T]
//       [--errors S F R SEED] [--refracting R CAP SUBSTRATE IOR] [--caps-to-sensor] [--reference]
//       [--every-lens] [--error-anchors N] [--no-symmetry] [--turn DEG] [--shift X_MM Y_MM] [--check N] [--csv OUT]
//
// --offset shifts the sensor (sensor { offset }): a crop of a larger raw away from its centre,
// e.g. its corner. --turn and --shift turn the array about the axis and move it across
// (microlens_array { rotate <0, 0, DEG> translate <X, Y, 0> }). --errors gives the array
// manufacturing errors (errors { position S focal_length F rotation R seed SEED }). --reference
// measures every lens from scratch (reuse_neighbours false: the integration as it was before the
// neighbours' radii were reused). --refracting replaces the thin
// microlenses by plano-convex caps (lens { surface { radius R } thickness CAP ior IOR substrate
// SUBSTRATE }, the curved side towards the scene, or towards the sensor with --caps-to-sensor; F_MM of
// --array is then unused). Refracting lenses on an array without errors are interpolated between
// anchors (MicroimageOptions::anchor_step); --every-lens measures every lens instead (anchor_step 0).
// --error-anchors N: refracting lenses with errors corrected from Jacobian anchors N lenses apart
// (MicroimageOptions::error_anchor_step; without it every such lens is measured).
// Refracting lenses on an array centred on the axis are measured in one quarter of it only, the
// others mirrored (MicroimageOptions::symmetry), and one turned or moved off the axis has its anchors
// measured in the same array turned back onto the axis; --no-symmetry measures each lens where it is.
// --check N measures N lenses of the picture each (never interpolated: measured_microimages), drawn
// at random from a fixed seed, and the picture's four corner lenses, and adds to the JSON the largest
// differences of the run's answer from theirs (check_du_px, check_dv_px, check_fraction) and the
// CPU seconds the check took (not counted in cpu_s).
// --brute CELL STEP measures the check's lenses once more by brute force, independently of the
// truth's boundary search: the renderer's own ray (generate_ray_unaimed through the lens, a sensor
// point lit through its own lens only, as the renderer counts it) from every point of a sensor
// grid STEP pixels apart over a square 2.5 pitches wide about the lens's lattice centre, at each of
// CELL x CELL cell points (the midpoint rule on the renderer's map of the cell): the lit points'
// centroid. It adds the largest differences of the run's answer and of the check's from it
// (brute_du_px, brute_dv_px, brute_check_du_px, brute_check_dv_px) and its CPU seconds.
// --brute-jittered draws each cell point at random in its stratum of the midpoint rule, anew for each
// sensor point (from a hash of the lens, the sensor point and the stratum): a rule that shares no
// cell points with the truth's, so that where a lens's light is cut across the cell (displaced
// neighbours, paths that leave the cell) the two do not step together.

#include <chrono>
#include <cmath>
#include <cstdint>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "bench/bench_camera.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/core/threads.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/optics.h"
#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/truth/microimages.h"

namespace {

using namespace plenoptic;

struct Options {
    bench::CameraOptions camera;
    double pitch_mm = 0, focal_mm = 0, distance_mm = 0;
    double offset_mm[2] = {0, 0};
    double turn_deg = 0, shift_mm[2] = {0, 0};
    int threads = 0;
    bench::ErrorsOption errors;
    bool reference = false;
    bool every_lens = false;
    bool no_symmetry = false;
    int check = 0;
    int anchor_step = -1, refracting_points = 0, check_points = 0, error_anchor_step = 0;
    int brute_points = 0;
    double brute_step_px = 0;
    bool brute_jittered = false;
    bench::RefractingOption refracting;
    std::string csv;
};

bool parse(int argc, char** argv, Options* o)
{
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        const int left = argc - a - 1;
        if (bench::read_camera_option(argc, argv, &a, &o->camera) ||
            bench::read_refracting_option(argc, argv, &a, &o->refracting) ||
            bench::read_errors_option(argc, argv, &a, &o->errors))
            continue;
        if (arg == "--array" && left >= 3) {
            o->pitch_mm = std::atof(argv[++a]);
            o->focal_mm = std::atof(argv[++a]);
            o->distance_mm = std::atof(argv[++a]);
        } else if (arg == "--offset" && left >= 2) {
            o->offset_mm[0] = std::atof(argv[++a]);
            o->offset_mm[1] = std::atof(argv[++a]);
        } else if (arg == "--turn" && left >= 1) {
            o->turn_deg = std::atof(argv[++a]);
        } else if (arg == "--shift" && left >= 2) {
            o->shift_mm[0] = std::atof(argv[++a]);
            o->shift_mm[1] = std::atof(argv[++a]);
        } else if (arg == "--threads" && left >= 1)
            o->threads = std::atoi(argv[++a]);
        else if (arg == "--reference")
            o->reference = true;
        else if (arg == "--every-lens")
            o->every_lens = true;
        else if (arg == "--no-symmetry")
            o->no_symmetry = true;
        else if (arg == "--check-points" && left >= 1)
            o->check_points = std::atoi(argv[++a]);
        else if (arg == "--anchor-step" && left >= 1)
            o->anchor_step = std::atoi(argv[++a]);
        else if (arg == "--error-anchors" && left >= 1)
            o->error_anchor_step = std::atoi(argv[++a]);
        else if (arg == "--points" && left >= 1)
            o->refracting_points = std::atoi(argv[++a]);
        else if (arg == "--brute" && left >= 2) {
            o->brute_points = std::atoi(argv[++a]);
            o->brute_step_px = std::atof(argv[++a]);
        } else if (arg == "--brute-jittered")
            o->brute_jittered = true;
        else if (arg == "--check" && left >= 1)
            o->check = std::atoi(argv[++a]);
        else if (arg == "--csv" && left >= 1)
            o->csv = argv[++a];
        else
            return false;
    }
    return o->camera.complete() && o->pitch_mm > 0 && o->focal_mm > 0 && o->distance_mm > 0 && o->threads >= 0 &&
           o->check >= 0 && o->brute_points >= 0 && (o->brute_points == 0 || (o->brute_step_px > 0 && o->check > 0));
}

// The lens's microimage centroid by brute force (--brute): false when no grid point is lit.
// A number in [0, 1) from four integers (splitmix64's finaliser over their mix): the same for the same
// arguments on any thread.
double hashed_uniform(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d)
{
    std::uint64_t z = a * 0x9e3779b97f4a7c15ull ^ (b + 0x632be59bd9b4e019ull) * 0xbf58476d1ce4e5b9ull ^
                      (c + 0x8cb92ba72f3d8dd7ull) * 0x94d049bb133111ebull ^ (d + 0x2545f4914f6cdd1dull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return double(z >> 11) * (1.0 / 9007199254740992.0);
}

bool brute_centroid(const PlenopticCamera& m, LensIndex lens, int cell_points, double step_px, bool jittered,
                    int threads, double* u_px, double* v_px)
{
    const MicroimageCentre c = microimage_centre_px(m, lens);
    const double half = 1.25 * m.array.pitch_mm / m.sensor.pixel_size_mm[0];
    const int n = int(std::ceil(2 * half / step_px));
    struct Sum {
        double count = 0, u = 0, v = 0;
    };
    std::vector<Sum> sums(std::size_t(std::max(1, threads)));
    auto work = [&](int t) {
        Sum& sum = sums[std::size_t(t)];
        for (int j = t; j < n; j += int(sums.size()))
            for (int i = 0; i < n; ++i) {
                // Corner convention: pixel (i, j) spans [i, i + 1) x [j, j + 1).
                const double u = c.u + 0.5 - half + (i + 0.5) * step_px, v = c.v + 0.5 - half + (j + 0.5) * step_px;
                if (!m.overlap.modelled) {
                    const OwnLens own = own_lens(m, m.sensor.point(u, v));
                    if (!(own.found && own.lens == lens))
                        continue;
                }
                for (int b = 0; b < cell_points; ++b)
                    for (int a = 0; a < cell_points; ++a) {
                        // The cell point: the stratum's middle, or (--brute-jittered) a point drawn in
                        // it for this sensor point alone, so that no edge of the lens's light lines up
                        // with the strata.
                        double ja = 0.5, jb = 0.5;
                        if (jittered) {
                            const std::uint64_t key = std::uint64_t(j) * 1000003u + std::uint64_t(i);
                            const std::uint64_t where = std::uint64_t(b) * 65537u + std::uint64_t(a);
                            ja = hashed_uniform(std::uint64_t(lens.k), std::uint64_t(lens.l), key, 2 * where);
                            jb = hashed_uniform(std::uint64_t(lens.k), std::uint64_t(lens.l), key, 2 * where + 1);
                        }
                        const CameraSample sample{u, v, (a + ja) / cell_points, (b + jb) / cell_points};
                        if (generate_ray_unaimed(m, 0, 0, sample, &lens).passed) {
                            sum.count += 1;
                            sum.u += u;
                            sum.v += v;
                        }
                    }
            }
    };
    run_on_threads(int(sums.size()), work);
    Sum total;
    for (const Sum& sum : sums) {
        total.count += sum.count;
        total.u += sum.u;
        total.v += sum.v;
    }
    if (!(total.count > 0))
        return false;
    *u_px = total.u / total.count - 0.5;  // centre convention, as the truth's
    *v_px = total.v / total.count - 0.5;
    return true;
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
                             "         --sensor W H PIXEL_MM --array PITCH_MM F_MM D_MM [--thick] [--offset X_MM Y_MM]\n"
                             "         [--threads T] [--errors S F R SEED] [--refracting R CAP SUBSTRATE IOR]\n"
                             "         [--caps-to-sensor] [--reference] [--every-lens] [--no-symmetry] [--turn DEG]\n"
                             "         [--shift X_MM Y_MM] [--check N] [--check-points N] [--brute CELL STEP_PX]\n"
                             "         [--brute-jittered]\n"
                             "         [--csv OUT]\n");
        return 2;
    }
    Prescription lens;
    if (!bench::read_lens_file("plenoptic_microimage_truth", o.camera.lens_file, &lens))
        return 1;
    bench::LensFileCamera camera;
    camera.options = o.camera;
    camera.pitch_mm = o.pitch_mm;
    camera.focal_mm = o.focal_mm;
    camera.distance_mm = o.distance_mm;
    CameraParams p = bench::camera_params(camera, lens);
    p.sensor.offset_mm[0] = o.offset_mm[0];
    p.sensor.offset_mm[1] = o.offset_mm[1];
    bench::use_refracting(o.refracting, &p);
    p.array.rotate_deg[2] = o.turn_deg;
    p.array.translate_mm[0] = o.shift_mm[0];
    p.array.translate_mm[1] = o.shift_mm[1];
    bench::use_errors(o.errors, &p);
    const std::string error = check_camera(p);
    if (!error.empty()) {
        std::fprintf(stderr, "plenoptic_microimage_truth: %s\n", error.c_str());
        return 1;
    }
    const PlenopticCamera m = with_film(make_camera(p), o.camera.width, o.camera.height);
    MicroimageOptions options = default_microimage_options();
    options.threads = o.threads;
    options.reuse_neighbours = !o.reference;
    if (o.anchor_step >= 0)
        options.anchor_step = o.anchor_step;
    options.error_anchor_step = o.error_anchor_step;
    if (o.refracting_points > 0)
        options.refracting_points = o.refracting_points;
    if (o.no_symmetry)
        options.symmetry = false;
    if (o.every_lens)
        options.anchor_step = 0;

    const double cpu0 = cpu_seconds();
    const auto wall0 = std::chrono::steady_clock::now();
    MicroimageWork work;
    const std::vector<MicroimageTruth> truth = microimage_truth(m, options, MicroimageProgress(), MicroimageCancel(),
                                                                nullptr, &work);
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
    // The check: random lenses of the picture and its corners, each measured.
    double check_du = 0, check_dv = 0, check_fraction = 0, check_cpu = 0;
    double brute_du = 0, brute_dv = 0, brute_check_du = 0, brute_check_dv = 0, brute_cpu = 0;
    std::size_t checked = 0;
    LensIndex worst{0, 0};
    if (o.check > 0 && !truth.empty()) {
        std::vector<std::size_t> which;
        std::uint64_t state = 0x9E3779B97F4A7C15ull;
        for (int i = 0; i < o.check; ++i) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            which.push_back(std::size_t((state >> 33) % truth.size()));
        }
        // The corners: the first and last lens of the first and the last row.
        std::size_t first_row_end = 0, last_row_start = truth.size() - 1;
        while (first_row_end + 1 < truth.size() && truth[first_row_end + 1].lens.l == truth[0].lens.l)
            ++first_row_end;
        while (last_row_start > 0 && truth[last_row_start - 1].lens.l == truth.back().lens.l)
            --last_row_start;
        which.push_back(0);
        which.push_back(first_row_end);
        which.push_back(last_row_start);
        which.push_back(truth.size() - 1);
        std::vector<LensIndex> lenses;
        for (std::size_t i : which)
            lenses.push_back(truth[i].lens);
        MicroimageOptions exact = options;
        exact.anchor_step = 0;
        if (o.check_points > 0)
            exact.refracting_points = o.check_points;
        const double c0 = cpu_seconds();
        const std::vector<MicroimageTruth> each = measured_microimages(m, lenses, exact);
        check_cpu = cpu_seconds() - c0;
        for (std::size_t i = 0; i < which.size(); ++i) {
            const MicroimageTruth& a = truth[which[i]];
            const MicroimageTruth& b = each[i];
            if (a.lit != b.lit) {
                std::fprintf(stderr, "plenoptic_microimage_truth: lens (%lld, %lld) lit %d, measured %d\n",
                             (long long)a.lens.k, (long long)a.lens.l, int(a.lit), int(b.lit));
                check_du = check_dv = INFINITY;
            }
            check_fraction = std::max(check_fraction, std::fabs(a.lit_fraction - b.lit_fraction));
            if (a.lit && b.lit) {
                const double d = std::max(std::fabs(a.u_px - b.u_px), std::fabs(a.v_px - b.v_px));
                if (d > std::max(check_du, check_dv))
                    worst = a.lens;
                check_du = std::max(check_du, std::fabs(a.u_px - b.u_px));
                check_dv = std::max(check_dv, std::fabs(a.v_px - b.v_px));
            }
            ++checked;
        }
        if (o.brute_points > 0) {
            const double b0 = cpu_seconds();
            const int threads = thread_count(o.threads);
            for (std::size_t i = 0; i < which.size(); ++i) {
                const MicroimageTruth& a = truth[which[i]];
                const MicroimageTruth& b = each[i];
                double u, v;
                if (!brute_centroid(m, a.lens, o.brute_points, o.brute_step_px, o.brute_jittered, threads, &u, &v)) {
                    if (a.lit)
                        brute_du = brute_dv = INFINITY;
                    continue;
                }
                brute_du = std::max(brute_du, std::fabs(a.u_px - u));
                brute_dv = std::max(brute_dv, std::fabs(a.v_px - v));
                brute_check_du = std::max(brute_check_du, std::fabs(b.u_px - u));
                brute_check_dv = std::max(brute_check_dv, std::fabs(b.v_px - v));
            }
            brute_cpu = cpu_seconds() - b0;
        }
    }
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    if (checked > 0)
        std::printf("{\"checked\": %zu, \"check_du_px\": %.3g, \"check_dv_px\": %.3g, \"check_fraction\": %.3g, "
                    "\"check_cpu_s\": %.3f, \"check_worst_lens\": [%lld, %lld]}\n",
                    checked, check_du, check_dv, check_fraction, check_cpu, (long long)worst.k, (long long)worst.l);
    if (checked > 0 && o.brute_points > 0)
        std::printf("{\"brute_points\": %d, \"brute_step_px\": %g, \"brute_jittered\": %s, \"brute_du_px\": %.3g, \"brute_dv_px\": %.3g, "
                    "\"brute_check_du_px\": %.3g, \"brute_check_dv_px\": %.3g, \"brute_cpu_s\": %.3f}\n",
                    o.brute_points, o.brute_step_px, o.brute_jittered ? "true" : "false", brute_du, brute_dv, brute_check_du, brute_check_dv, brute_cpu);
    std::printf("{\"size\": [%d, %d], \"offset_mm\": [%.9g, %.9g], \"lenses\": %zu, \"lit_lenses\": %zu, "
                "\"threads\": %d, \"wall_s\": %.3f, \"cpu_s\": %.3f, \"peak_rss_mib\": %.1f, \"anchors\": %zu, "
                "\"interpolated\": %zu, \"measured\": %zu, \"quarter_lenses\": %zu, \"corrected\": %zu, "
                "\"error_anchors\": %zu}\n",
                o.camera.width, o.camera.height, o.offset_mm[0], o.offset_mm[1], truth.size(), lit, o.threads, wall, cpu,
                usage.ru_maxrss / 1024.0, work.anchors, work.interpolated, work.measured, work.quarter_lenses,
                work.corrected, work.error_anchors);
    return 0;
}
