// SPDX-License-Identifier: AGPL-3.0-or-later
// Explicit camera samples, the concentric disc map, and focal_blur-style adaptive thresholds.

#ifndef PLENOPTIC_SAMPLING_H
#define PLENOPTIC_SAMPLING_H

#include <cstdint>
#include <vector>

#include "plenoptic/core/vec.h"

namespace plenoptic {

// SplitMix64's step and finaliser: a bijection of 64-bit words that mixes every bit into every
// other (sample rotations, the arrays' manufacturing errors).
inline std::uint64_t mix64(std::uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}


// One sample of a pixel: a point on the pixel and a point on the aperture being sampled
// (a microlens cell, or the main-lens disc when there is no array).
struct CameraSample {
    double pixel_u, pixel_v;  // offset inside the pixel, [0,1) each; (0.5, 0.5) is its centre
    double lens_u, lens_v;    // [0,1)^2 over the aperture; (0.5, 0.5) maps to its centre
};

// Sample n of `count` samples of pixel (i, j). Depends on (i, j, n, count, stream) only: no
// state, so any thread order gives the same image. A 1-sample pixel gets exactly the pixel centre
// and the aperture centre; otherwise point n of the Halton sequence (bases 5, 7 for the pixel,
// 2, 3 for the aperture) with a per-pixel Cranley-Patterson rotation from an integer hash of
// (i, j) and, for streams other than 0, of the stream: each stream of a pixel is a whole
// low-discrepancy sequence of its own (overlap modelling gives each lens of a pixel one).
CameraSample make_sample(int i, int j, int n, int count, int stream = 0);

// Shirley-Chiu concentric map of [0,1)^2 onto the unit disc; (0.5, 0.5) -> (0, 0).
Vec2 concentric_disc(double u, double v);

// Inverse of the complemented chi-square distribution, as cephes' chdtri (which POV-Ray's
// focal_blur calls): the x with P(chi2_dof > x) = q, for 0 < q < 1 and dof > 0 (Boost.Math's
// chi-square quantile of the complement). q <= 0 gives infinity, q >= 1 gives 0.
// chi2_upper_quantile(0.9, 1) = 0.015791, chi2_upper_quantile(0.1, 10) = 15.987.
double chi2_upper_quantile(double q, double dof);

// adaptive_thresholds uses chi2_upper_quantile up to this many degrees of freedom and the
// Wilson-Hilferty approximation above (relative error below 6e-6 for any confidence in
// [1e-9, 1 - 1e-9], below 2e-7 for confidences in [0.01, 0.99]), so that a million-sample
// table still takes milliseconds.
const int kExactChi2Dof = 10000;

// Stop thresholds for adaptive sampling, with the meaning focal_blur gives them in POV-Ray:
// threshold[n-1] = variance * chdtri(n, confidence) / chdtri(samples_max - 1, confidence);
// sampling stops when the variance of the mean of n samples is below threshold[n-1] in every
// channel. A single sample (samples_max == 1) gets threshold 0.
std::vector<double> adaptive_thresholds(int samples_max, double confidence, double variance);

} // namespace plenoptic

#endif
