// SPDX-License-Identifier: AGPL-3.0-or-later
// Deterministic low-discrepancy camera samples, the concentric disc map and the adaptive
// thresholds (chi-square quantiles from Boost.Math).

#include "plenoptic/core/sampling.h"

#include <cmath>
#include <cstdint>
#include <limits>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

namespace plenoptic {

namespace {

// Top 53 bits as a double in [0, 1).
double to_unit(std::uint64_t bits) { return double(bits >> 11) * (1.0 / 9007199254740992.0); }

// Van der Corput radical inverse of n in base Base, in [0, 1). A compile-time base turns the
// divisions into multiplications.
template <std::uint32_t Base>
double radical_inverse(std::uint32_t n)
{
    const double inverse = 1.0 / Base;
    double scale = inverse;
    double value = 0;
    while (n > 0) {
        value += double(n % Base) * scale;
        n /= Base;
        scale *= inverse;
    }
    return value;
}

} // namespace

CameraSample make_sample(int i, int j, int n, int count, int stream)
{
    if (count <= 1)
        return CameraSample{0.5, 0.5, 0.5, 0.5};

    // Halton bases: the aperture gets the two best-distributed (2, 3), because the aperture
    // integral carries the defocus blur; the pixel area gets 5 and 7.
    const std::uint32_t index = std::uint32_t(n);
    const double halton[4] = {radical_inverse<5>(index), radical_inverse<7>(index), radical_inverse<2>(index),
                              radical_inverse<3>(index)};
    const std::uint64_t key = (std::uint64_t(std::uint32_t(i)) << 32) | std::uint64_t(std::uint32_t(j));
    double value[4];
    // Stream 0 keeps the pixel's own rotation; another stream hashes its number in first.
    std::uint64_t hash = key;
    if (stream != 0)
        hash = mix64(key ^ (std::uint64_t(std::uint32_t(stream)) * 0xD6E8FEB86659FD93ull));
    for (int d = 0; d < 4; ++d) {
        hash = mix64(hash);
        // Cranley-Patterson rotation: shift the whole point set by a per-pixel offset, modulo 1.
        double x = halton[d] + to_unit(hash);
        if (x >= 1)
            x -= 1;
        value[d] = x;
    }
    return CameraSample{value[0], value[1], value[2], value[3]};
}

Vec2 concentric_disc(double u, double v)
{
    const double a = 2 * u - 1;
    const double b = 2 * v - 1;
    if (a == 0 && b == 0)
        return Vec2{0, 0};
    double r, phi;
    if (std::fabs(a) > std::fabs(b)) {
        r = a;
        phi = (kPi / 4) * (b / a);
    } else {
        r = b;
        phi = kPi / 2 - (kPi / 4) * (a / b);
    }
    return Vec2{r * std::cos(phi), r * std::sin(phi)};
}

namespace {

// Boost.Math without its default promotion of double arguments to long double (x87 arithmetic,
// about 5 times slower here, for digits a threshold does not need), and with domain errors
// and overflow reported as NaN and infinity rather than thrown: the callers check their
// arguments first anyway.
typedef boost::math::policies::policy<boost::math::policies::promote_double<false>,
                                      boost::math::policies::domain_error<boost::math::policies::ignore_error>,
                                      boost::math::policies::overflow_error<boost::math::policies::ignore_error>>
    QuantilePolicy;

// Wilson-Hilferty approximation of the upper-tail chi-square quantile from the normal quantile
// z of the upper tail: see kExactChi2Dof for its error.
double wilson_hilferty(double z, double dof)
{
    const double c = 2 / (9 * dof);
    const double cube = 1 - c + z * std::sqrt(c);
    return dof * cube * cube * cube;
}

} // namespace

double chi2_upper_quantile(double q, double dof)
{
    if (!(q > 0))
        return std::numeric_limits<double>::infinity();
    if (!(q < 1))
        return 0;
    const boost::math::chi_squared_distribution<double, QuantilePolicy> chi2(dof);
    return boost::math::quantile(boost::math::complement(chi2, q));
}

std::vector<double> adaptive_thresholds(int samples_max, double confidence, double variance)
{
    std::vector<double> threshold(samples_max > 0 ? samples_max : 1, 0.0);
    if (samples_max <= 1)
        return threshold;
    // POV-Ray calls cephes' chdtri, the complemented (upper-tail) inverse. Above kExactChi2Dof
    // degrees of freedom, Wilson-Hilferty from the normal quantile, computed once.
    const boost::math::normal_distribution<double, QuantilePolicy> normal;
    const double z = boost::math::quantile(boost::math::complement(normal, confidence));
    auto quantile = [&](int dof) {
        return dof > kExactChi2Dof ? wilson_hilferty(z, dof) : chi2_upper_quantile(confidence, dof);
    };
    const double scale = variance / quantile(samples_max - 1);
    for (int n = 1; n <= samples_max; ++n)
        threshold[n - 1] = scale * quantile(n);
    return threshold;
}

} // namespace plenoptic
