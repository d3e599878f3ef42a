// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic_convolution: diffraction's convolution of the picture (sensor/diffraction.h) alone,
// timed, for BENCHMARKS.md ("Diffraction by tiles"). The picture is W x H x 3 floats of
// microimage-like discs (the shape a raw behind an array has); the kernels are the Airy patterns
// of the three radii given in pixels. It prints one JSON object: wall and CPU seconds and the
// process's peak RSS after the convolution. --direct runs instead the direct sum row by row, as
// the convolution was computed before it went by tiles (the picture copied whole, every output a
// double sum over the window): the "before" of the benchmark. --compare runs both on copies and
// reports how many values are equal and the largest difference relative to the picture's largest
// value (the tiles' result is the direct sum's within float rounding).
//
//   plenoptic_convolution --size W H --radii R G B [--threads T] [--direct | --compare]

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "plenoptic/core/threads.h"
#include "plenoptic/sensor/diffraction.h"

namespace {

using namespace plenoptic;

// The convolution as it was computed before tiles: every row of every channel summed directly
// from a whole copy of the picture, rows shared among the threads.
void direct_convolution(std::vector<float>& picture, int W, int H, int channels, const AiryKernel* kernels, int threads)
{
    const std::vector<float> source(picture);
    std::atomic<int> next_row(0);
    run_on_threads(threads, [&](int) {
        for (int j = next_row++; j < H; j = next_row++)
            for (int c = 0; c < channels; ++c) {
                const AiryKernel& k = kernels[c];
                const int w = 2 * k.kx + 1;
                for (int i = 0; i < W; ++i) {
                    double sum = 0;
                    for (int dy = std::max(-k.ky, -j); dy <= std::min(k.ky, H - 1 - j); ++dy) {
                        const float* row = &source[(size_t(j + dy) * W) * channels + c];
                        const double* weights = &k.weights[size_t((dy + k.ky) * w + k.kx)];
                        for (int dx = std::max(-k.kx, i - (W - 1)); dx <= std::min(k.kx, i); ++dx)
                            sum += weights[dx] * row[size_t(i - dx) * channels];
                    }
                    picture[(size_t(j) * W + i) * channels + c] = float(sum);
                }
            }
    });
}

std::vector<float> test_picture(int W, int H)
{
    std::vector<float> picture(size_t(W) * H * 3, 0.0f);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const double u = std::fmod(i, 14.0) - 7, v = std::fmod(j, 12.0) - 6;
            if (u * u + v * v < 30)
                for (int c = 0; c < 3; ++c)
                    picture[(size_t(j) * W + i) * 3 + c] = float(0.3 + 0.2 * c + 0.001 * ((i * 7 + j * 13) % 97));
        }
    return picture;
}

double cpu_seconds()
{
    return double(std::clock()) / CLOCKS_PER_SEC;
}

long peak_rss_kib()
{
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss;
}

[[noreturn]] void usage(const char* message)
{
    std::fprintf(stderr, "plenoptic_convolution: %s\nusage: plenoptic_convolution --size W H --radii R G B [--threads T] "
                         "[--direct | --compare]\n", message);
    std::exit(2);
}

} // namespace

int main(int argc, char** argv)
{
    int W = 0, H = 0, threads = thread_count(0);
    double radii[3] = {0, 0, 0};
    bool direct = false, compare = false;
    for (int a = 1; a < argc; ++a) {
        const std::string arg = argv[a];
        auto number = [&](int k) {
            if (a + k >= argc)
                usage((arg + " needs " + std::to_string(k) + " value(s)").c_str());
            char* end = nullptr;
            const double v = std::strtod(argv[a + k], &end);
            if (*end != '\0' || !(v > 0))
                usage((arg + ": not a positive number: " + argv[a + k]).c_str());
            return v;
        };
        if (arg == "--size") {
            W = int(number(1));
            H = int(number(2));
            a += 2;
        } else if (arg == "--radii") {
            for (int c = 0; c < 3; ++c)
                radii[c] = number(c + 1);
            a += 3;
        } else if (arg == "--threads") {
            threads = int(number(1));
            a += 1;
        } else if (arg == "--direct") {
            direct = true;
        } else if (arg == "--compare") {
            compare = true;
        } else {
            usage(("unknown argument " + arg).c_str());
        }
    }
    if (W <= 0 || H <= 0 || !(radii[0] > 0))
        usage("--size and --radii are needed");
    if (direct && compare)
        usage("--direct and --compare exclude each other");
    AiryKernel kernels[3];
    for (int c = 0; c < 3; ++c) {
        if (radii[c] > kMaxAiryRadiusPx)
            usage("an Airy radius is at most 16 pixels");
        kernels[c] = airy_kernel(radii[c], radii[c]);
    }
    std::vector<float> picture = test_picture(W, H);
    std::vector<float> reference;
    if (compare)
        reference = picture;
    const double cpu0 = cpu_seconds();
    const auto wall0 = std::chrono::steady_clock::now();
    if (direct)
        direct_convolution(picture, W, H, 3, kernels, threads);
    else if (!convolve_channels(picture, W, H, 3, kernels, nullptr, threads))
        usage("the convolution failed");
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    const double cpu = cpu_seconds() - cpu0;
    const long peak = peak_rss_kib();
    std::printf("{\"method\": \"%s\", \"width\": %d, \"height\": %d, \"kernel_px\": [%d, %d, %d], \"threads\": %d, "
                "\"wall_s\": %.3f, \"cpu_s\": %.3f, \"peak_rss_mib\": %.1f",
                direct ? "direct" : "tiles", W, H, 2 * kernels[0].kx + 1, 2 * kernels[1].kx + 1, 2 * kernels[2].kx + 1, threads,
                wall, cpu, peak / 1024.0);
    if (compare) {
        direct_convolution(reference, W, H, 3, kernels, threads);
        size_t equal = 0;
        double largest = 0, worst = 0;
        for (size_t n = 0; n < picture.size(); ++n) {
            equal += picture[n] == reference[n];
            largest = std::max(largest, double(reference[n]));
            worst = std::max(worst, std::fabs(double(picture[n]) - reference[n]));
        }
        std::printf(", \"equal_values\": %zu, \"values\": %zu, \"largest_difference_relative\": %.3g", equal, picture.size(),
                    largest > 0 ? worst / largest : 0.0);
    }
    std::printf("}\n");
    return 0;
}
