// SPDX-License-Identifier: AGPL-3.0-or-later
// Explicit camera samples, the concentric disc map, and focal_blur-style adaptive thresholds.

#ifndef PLENOPTIC_SAMPLING_H
#define PLENOPTIC_SAMPLING_H

#include <vector>

#include "plenoptic_vec.h"

namespace plenoptic {

// One sample of a pixel: a point on the pixel and a point on the aperture being sampled
// (a microlens cell, or the main-lens disc when there is no array).
struct CameraSample {
    double pixel_u, pixel_v;  // offset inside the pixel, [0,1) each; (0.5, 0.5) is its centre
    double lens_u, lens_v;    // [0,1)^2 over the aperture; (0.5, 0.5) maps to its centre
};

// Sample n of `count` samples of pixel (i, j). Depends on (i, j, n, count) only: no state, so
// any thread order gives the same image. A 1-sample pixel gets exactly the pixel centre and the
// aperture centre; otherwise point n of the Halton sequence (bases 5, 7 for the pixel, 2, 3 for
// the aperture) with a per-pixel Cranley-Patterson rotation from an integer hash of (i, j).
CameraSample make_sample(int i, int j, int n, int count);

// Shirley-Chiu concentric map of [0,1)^2 onto the unit disc; (0.5, 0.5) -> (0, 0).
Vec2 concentric_disc(double u, double v);

// Natural logarithm of the gamma function, a > 0 (thread-safe, unlike std::lgamma).
double log_gamma(double a);

// Regularised lower incomplete gamma function P(a, x), a > 0, x >= 0.
double regularized_lower_gamma(double a, double x);

// Standard normal quantile: the z with Phi(z) = p.
double normal_quantile(double p);

// Above this many degrees of freedom chi2_quantile uses the Wilson-Hilferty approximation.
const double kExactChi2Dof = 1000;

// Chi-square quantile (lower tail): the x with P(chi2_dof <= x) = p, 0 < p < 1.
// chi2_quantile(0.9, 1) = 2.7055, chi2_quantile(0.9, 10) = 15.987.
double chi2_quantile(double p, double dof);

// Inverse of the complemented chi-square distribution, as cephes' chdtri (and so POV-Ray's):
// the x with P(chi2_dof > x) = q, i.e. chi2_quantile(1 - q, dof).
double chi2_upper_quantile(double q, double dof);

// Stop thresholds for adaptive sampling, with the meaning focal_blur gives them in POV-Ray:
// threshold[n-1] = variance * chdtri(n, confidence) / chdtri(samples_max - 1, confidence);
// sampling stops when the variance of the mean of n samples is below threshold[n-1] in every
// channel. A single sample (samples_max == 1) gets threshold 0.
std::vector<double> adaptive_thresholds(int samples_max, double confidence, double variance);

} // namespace plenoptic

#endif
