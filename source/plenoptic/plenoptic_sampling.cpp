// SPDX-License-Identifier: AGPL-3.0-or-later
// Deterministic low-discrepancy camera samples, the concentric disc map and chi-square quantiles.

#include "plenoptic_sampling.h"

#include <cmath>
#include <cstdint>
#include <limits>

namespace plenoptic {

namespace {

const double kPi = 3.14159265358979323846;

// splitmix64's finaliser: a well-mixed 64-bit hash.
std::uint64_t mix64(std::uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

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

CameraSample make_sample(int i, int j, int n, int count)
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
    std::uint64_t hash = key;
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

double log_gamma(double a)
{
    // Shift up to a >= 15, then Stirling's series; no global state (unlike lgamma's signgam).
    double shift = 0;
    while (a < 15) {
        shift += std::log(a);
        a += 1;
    }
    const double inv = 1 / a;
    const double inv2 = inv * inv;
    const double series = inv * (1.0 / 12 - inv2 * (1.0 / 360 - inv2 * (1.0 / 1260 - inv2 * (1.0 / 1680))));
    return (a - 0.5) * std::log(a) - a + 0.91893853320467274178 + series - shift;
}

double regularized_lower_gamma(double a, double x)
{
    if (!(x > 0))
        return 0;
    if (std::isinf(x))
        return 1;
    const double log_prefix = a * std::log(x) - x - log_gamma(a);
    if (x < a + 1) {
        // Series: P = x^a e^-x / Gamma(a+1) * sum x^n / ((a+1)...(a+n)).
        double term = 1 / a;
        double sum = term;
        for (int n = 1; n < 100000; ++n) {
            term *= x / (a + n);
            sum += term;
            if (std::fabs(term) < std::fabs(sum) * 1e-17)
                break;
        }
        return sum * std::exp(log_prefix);
    }
    // Continued fraction for Q = 1 - P (modified Lentz).
    const double tiny = 1e-300;
    double b = x + 1 - a;
    double c = 1 / tiny;
    double d = 1 / b;
    double h = d;
    for (int n = 1; n < 100000; ++n) {
        const double an = -n * (n - a);
        b += 2;
        d = an * d + b;
        if (std::fabs(d) < tiny)
            d = tiny;
        c = b + an / c;
        if (std::fabs(c) < tiny)
            c = tiny;
        d = 1 / d;
        const double delta = d * c;
        h *= delta;
        if (std::fabs(delta - 1) < 1e-17)
            break;
    }
    return 1 - std::exp(log_prefix) * h;
}

double normal_quantile(double p)
{
    if (!(p > 0))
        return -std::numeric_limits<double>::infinity();
    if (!(p < 1))
        return std::numeric_limits<double>::infinity();
    // Bisection on the normal CDF, 0.5 erfc(-z / sqrt 2), over a bracket wide enough for doubles.
    double low = -40, high = 40;
    for (int iteration = 0; iteration < 200; ++iteration) {
        const double mid = 0.5 * (low + high);
        if (mid <= low || mid >= high)
            break;
        if (0.5 * std::erfc(-mid / 1.41421356237309504880) < p)
            low = mid;
        else
            high = mid;
    }
    return 0.5 * (low + high);
}

namespace {

// Wilson-Hilferty approximation of the chi-square quantile from the normal quantile z: relative
// error far below 1e-5 above kExactChi2Dof degrees of freedom.
double wilson_hilferty(double z, double dof)
{
    const double c = 2 / (9 * dof);
    const double cube = 1 - c + z * std::sqrt(c);
    return dof * cube * cube * cube;
}

} // namespace

double chi2_quantile(double p, double dof)
{
    if (!(p > 0))
        return 0;
    if (!(p < 1))
        return std::numeric_limits<double>::infinity();
    if (dof > kExactChi2Dof)
        return wilson_hilferty(normal_quantile(p), dof);
    const double a = dof / 2;
    // Bracket, then bisect on the CDF, which is monotonic: robust, and fast enough for a table
    // computed once per render.
    double low = 0;
    double high = dof + 10;
    while (regularized_lower_gamma(a, high / 2) < p)
        high *= 2;
    for (int iteration = 0; iteration < 200; ++iteration) {
        const double mid = 0.5 * (low + high);
        if (mid <= low || mid >= high || high - low <= 1e-15 * high)
            break;
        if (regularized_lower_gamma(a, mid / 2) < p)
            low = mid;
        else
            high = mid;
    }
    return 0.5 * (low + high);
}

double chi2_upper_quantile(double q, double dof) { return chi2_quantile(1 - q, dof); }

std::vector<double> adaptive_thresholds(int samples_max, double confidence, double variance)
{
    std::vector<double> threshold(samples_max > 0 ? samples_max : 1, 0.0);
    if (samples_max <= 1)
        return threshold;
    // POV-Ray calls cephes' chdtri, the complemented (upper-tail) inverse: the lower-tail quantile
    // at 1 - confidence. The normal quantile is computed once for the large-dof approximation.
    const double p = 1 - confidence;
    const double z = normal_quantile(p);
    auto quantile = [&](double dof) { return dof > kExactChi2Dof ? wilson_hilferty(z, dof) : chi2_quantile(p, dof); };
    const double scale = variance / quantile(samples_max - 1);
    for (int n = 1; n <= samples_max; ++n)
        threshold[n - 1] = scale * quantile(n);
    return threshold;
}

} // namespace plenoptic
