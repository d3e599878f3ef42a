// SPDX-License-Identifier: AGPL-3.0-or-later
// The per-pixel sample loop of the plenoptic camera: fixed or adaptive, with overlap weighting.

#ifndef PLENOPTIC_PIXEL_H
#define PLENOPTIC_PIXEL_H

#include <algorithm>
#include <cstdint>

#include "plenoptic/camera/aim.h"
#include "plenoptic/camera/rays.h"

namespace plenoptic {

struct Rgbt {
    double r, g, b, t;
};

// Samples looked at, per traced sample, to measure how much of a partly vignetted pixel passes
// the apertures. They need no scene ray (a few hundred instructions each), and at a microimage's
// rim the vignetting, not the scene, is most of a pixel's error: 4 cuts it by more than half there.
const int kVignettingProbesPerSample = 4;

namespace detail {

// What the sample loop adds up for a pixel: r, g, b and t of the light the traced rays bring and,
// with N = 5, a white channel: each passing ray brings 1 there, so that channel is what the pixel
// would be in a world of radiance 1 (its white image value) from the very same samples.
template <int N>
struct Channels {
    double v[N];
};

template <int N>
inline Channels<N> zero_channels()
{
    Channels<N> c;
    for (int ch = 0; ch < N; ++ch)
        c.v[ch] = 0;
    return c;
}

// What `trace` returns for `ray`, as channels (the white channel 1).
template <int N, class TraceFn>
Channels<N> traced_plain(TraceFn& trace, const OpticsRay& ray)
{
    const Rgbt c = trace(ray);
    Channels<N> out;
    out.v[0] = c.r;
    out.v[1] = c.g;
    out.v[2] = c.b;
    out.v[3] = c.t;
    if (N == 5)
        out.v[N - 1] = 1;
    return out;
}

// The colour a ray brings, scaled by its weight (the sampled area of a real lens's exit pupil
// relative to its paraxial pupil; 1 for every other ray).
template <int N, class TraceFn>
Channels<N> traced(TraceFn& trace, const OpticsRay& ray)
{
    Channels<N> c = traced_plain<N>(trace, ray);
    if (ray.weight == 1)
        return c;
    for (int ch = 0; ch < N; ++ch)
        c.v[ch] *= ray.weight;
    return c;
}

// Running sums of one lens's samples.
template <int N>
struct SampleSums {
    double sum[N];
    double sum_sq[N];
    int count;
};

template <int N>
inline void add_sample(SampleSums<N>* s, const Channels<N>& c)
{
    for (int ch = 0; ch < N; ++ch) {
        s->sum[ch] += c.v[ch];
        s->sum_sq[ch] += c.v[ch] * c.v[ch];
    }
    ++s->count;
}

// The pixel value and, per channel, the variance of that estimate. One lens: the mean of its
// samples. Several lenses: the sum over lenses of the mean over each lens's samples (irradiance
// adds). Fewer samples than lenses (lens_sample's first round, unfinished): slot 0 has its sample
// and the other lenses sampled are a random choice among them (a rotation drawn per pixel), each
// equally likely, so their sum, scaled by (L - 1) over their number, is an unbiased estimate of
// the others' sum; slot 0's light (its own lens's, where most of a pixel's light comes from) is
// never scaled. With one sample only slot 0 counts (the 1-sample pixel's chief ray).
template <int N>
inline void estimate(const SampleSums<N>* sums, int lenses, double value[N], double variance[N])
{
    for (int ch = 0; ch < N; ++ch)
        value[ch] = variance[ch] = 0;
    int others = 0;  // lenses other than slot 0 with a sample
    for (int s = 1; s < lenses; ++s)
        others += sums[s].count > 0;
    const double scale = others > 0 ? double(lenses - 1) / others : 0;
    for (int s = 0; s < lenses; ++s) {
        const int n = sums[s].count;
        if (n == 0)
            continue;
        const double k = s == 0 ? 1 : scale;
        for (int ch = 0; ch < N; ++ch) {
            const double mean = sums[s].sum[ch] / n;
            value[ch] += k * mean;
            // Variance of the mean, as focal_blur computes it: (E[x^2] - E[x]^2) / n.
            variance[ch] += k * k * (sums[s].sum_sq[ch] / n - mean * mean) / n;
        }
    }
}

// `sum` scaled by `scale`, as channels.
template <int N>
inline Channels<N> scaled(const double sum[N], double scale)
{
    Channels<N> c;
    for (int ch = 0; ch < N; ++ch)
        c.v[ch] = sum[ch] * scale;
    return c;
}

// Which of a pixel's `others` lenses after slot 0 its samples visit first: a rotation drawn from
// the pixel and the sample stream (a hash: the same on every thread and in every tile).
inline int lens_rotation(int i, int j, int stream, int others)
{
    std::uint32_t h =
        std::uint32_t(i) * 0x9E3779B1u ^ std::uint32_t(j) * 0x85EBCA77u ^ std::uint32_t(stream) * 0xC2B2AE3Du;
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 12;
    h *= 0x297A2D39u;
    h ^= h >> 15;
    return int(h % std::uint32_t(others));
}

// Sample n of `count` samples of pixel (i, j) whose light comes through `lenses` lenses (overlap
// modelling). Samples go round the lenses, slot n mod L, except in the first round: there the
// first goes through slot 0 (the pixel's own lens) and the others through slots 1 .. L-1 in an
// order rotated per pixel (lens_rotation), so that when a pixel takes fewer samples than it has
// lenses, the lenses beyond its own that get one are a random choice (estimate scales their sum
// up, unbiased), not always the same neighbours; a round holds every lens once either way, so
// the points each lens gets are the same. Sample n goes through its lens as sample n / L of that
// lens's own stream of make_sample, so each lens gets a whole low-discrepancy pattern over the
// pixel and the aperture, and the lenses' shares differ by one sample at most. (Every L-th point
// of one Halton sequence is not such a pattern: with L = 2, the even points have their base-2
// coordinate, the aperture's u, all in one half of [0, 1).) With one lens this is exactly
// make_sample(i, j, n, count).
inline CameraSample lens_sample(int i, int j, int n, int count, int lenses, int* slot, int stream = 0)
{
    *slot = n % lenses;
    if (n < lenses && n > 0)
        *slot = 1 + (n - 1 + lens_rotation(i, j, stream, lenses - 1)) % (lenses - 1);
    // `count`, not the lens's share of it: only a 1-sample pixel is sampled at its centre, and a
    // lens that gets one sample of several gets a random point (point 0 of its rotated stream).
    return make_sample(i, j, n / lenses, count, stream + *slot);
}

// The samples one call of shade_samples takes: between min and max (fixed: min == max), from
// sample stream `stream` (make_sample; lens slot s of overlap modelling uses stream + s); `pixel_count`
// is the pixel's whole sample count, which decides whether the pixel is a 1-sample pixel (its centre
// and chief ray) or sampled over its area: a spectral band that gets 1 of a pixel's 16 samples
// takes a random point of the pixel and the aperture, as every other sample does.
struct SampleBudget {
    int min, max;
    int pixel_count;
    int stream;
};

// How many of samples from .. to-1 of pixel (i, j) pass the apertures through the pixel's own
// lenses (geometry only); *first is the first of them (-1 if none).
inline int passing_samples(const PlenopticCamera& model, int i, int j, int from, int to, int* first, int stream = 0)
{
    int passing = 0;
    *first = -1;
    for (int n = from; n < to; ++n) {
        const OpticsRay ray = model.generate_ray(i, j, make_sample(i, j, n, to, stream));
        if (ray.passed) {
            ++passing;
            if (*first < 0)
                *first = n;
        }
    }
    return passing;
}

// The pixel's value from the samples traced so far when some were blocked: the mean colour of the
// samples that passed, times the passing fraction measured over kVignettingProbesPerSample times
// as many sample points (a ratio estimate: the vignetting is known far better than the scene).
// `sum` holds the sums of the `passed` traced colours of samples 0 .. n-1. With none passed but
// some probe passing, that probe's sample is traced so the pixel is not black where light lands.
template <int N, class TraceFn>
Channels<N> vignetted_value(const PlenopticCamera& model, int i, int j, int n, int passed, double sum[N], TraceFn& trace,
                            int stream)
{
    const int probes = n * kVignettingProbesPerSample;
    int first_untraced;
    // Samples 0 .. n-1 were generated already: only the points after them are new.
    const int passing = passed + passing_samples(model, i, j, n, probes, &first_untraced, stream);
    if (passed == 0 && first_untraced >= 0) {
        const OpticsRay ray = model.generate_ray(i, j, make_sample(i, j, first_untraced, probes, stream));
        const Channels<N> c = detail::traced<N>(trace, ray);
        for (int ch = 0; ch < N; ++ch)
            sum[ch] = c.v[ch];
        passed = 1;
    }
    if (passed == 0)
        return zero_channels<N>();
    return scaled<N>(sum, double(passing) / probes / passed);
}

// Points a side of the grid over which a pixel's lit area is averaged (lit_area_value).
const int kLitAreaGrid = 4;

// The mean lit area (LitAreaTable) of pixel (i, j): the midpoint rule on a kLitAreaGrid square
// grid over the pixel. The lit area is smooth across a pixel (a kink where vignetting sets in at
// most), so the rule's error is second order in the pixel's size; a table look-up each, no trace.
inline double mean_lit_area(const PlenopticCamera& model, int i, int j)
{
    double total = 0;
    for (int b = 0; b < kLitAreaGrid; ++b)
        for (int a = 0; a < kLitAreaGrid; ++a)
            total += model.lit_area->at(model.sensor.point(i + (a + 0.5) / kLitAreaGrid, j + (b + 0.5) / kLitAreaGrid));
    return total / (kLitAreaGrid * kLitAreaGrid);
}

// The pixel's value behind a real lens with a lit-area table (PlenopticCamera::lit_area: no array, round
// stop), from its n > 1 samples: the mean colour of those that passed (`plain`: their colours
// without the ray weight) times the pixel's mean lit area (mean_lit_area). The samples that pass
// are spread uniformly over the pixel's lit (sensor point, pupil point) pairs, so their plain
// mean is the lit light's mean colour; the table knows the lit area everywhere, so the pixel's
// vignetting costs look-ups, not traces. With none passed, the first passing point of
// kVignettingProbesPerSample n points of its sample sequence is traced for the colour.
template <int N, class TraceFn>
Channels<N> lit_area_value(const PlenopticCamera& model, int i, int j, int n, int passed, const double plain[N],
                           TraceFn& trace, int stream)
{
    const double lit = mean_lit_area(model, i, j);
    if (!(lit > 0))
        return zero_channels<N>();
    if (passed > 0)
        return scaled<N>(plain, lit / passed);
    const int points = n * kVignettingProbesPerSample;
    for (int k = n; k < points; ++k) {
        const OpticsRay ray = model.generate_ray(i, j, make_sample(i, j, k, points, stream));
        if (ray.passed) {
            const Channels<N> c = traced_plain<N>(trace, ray);
            return scaled<N>(c.v, lit);
        }
    }
    return zero_channels<N>();
}

// shade_pixel's work for one camera and one budget of samples (see shade_pixel below), in N
// channels (r, g, b, t and, with N = 5, white). Adaptive stopping looks at r, g, b and t only.
template <int N, class TraceFn>
Channels<N> shade_samples(const PlenopticCamera& model, int i, int j, TraceFn& trace, const SampleBudget& budget)
{
    const int count = std::max(1, budget.max);
    const int stream = budget.stream;
    if (!model.sampling.adaptive && !model.overlap.modelled) {
        // Fixed count through the own lens: the plain mean, without the variance bookkeeping
        // (the common case, and the one whose cost is compared with the stock cameras).
        const bool lit_area = model.lit_area && budget.pixel_count > 1;
        double sum[N];
        for (int ch = 0; ch < N; ++ch)
            sum[ch] = 0;
        int passed = 0;
        for (int n = 0; n < count; ++n) {
            const OpticsRay ray = model.generate_ray(i, j, make_sample(i, j, n, budget.pixel_count, stream));
            if (ray.passed) {
                // With a lit-area table the colours are summed without the ray weight: the
                // pixel's lit area scales their mean (detail::lit_area_value).
                const Channels<N> c = lit_area ? traced_plain<N>(trace, ray) : detail::traced<N>(trace, ray);
                for (int ch = 0; ch < N; ++ch)
                    sum[ch] += c.v[ch];
                ++passed;
            }
        }
        if (lit_area)
            return lit_area_value<N>(model, i, j, count, passed, sum, trace, stream);
        // Aimed samples (camera/aim.h) carry weights, and choosing the probes' ratio estimate only
        // when some sample was blocked would bias the pixel by the weights that passed: their plain
        // mean is unbiased, and few of them are blocked.
        if (budget.pixel_count > 1 && passed < count && !model.sampling.aim)
            return vignetted_value<N>(model, i, j, count, passed, sum, trace, stream);
        Channels<N> mean;
        for (int ch = 0; ch < N; ++ch)
            mean.v[ch] = sum[ch] / count;
        return mean;
    }

    LensIndex lenses[kMaxOverlapLenses];
    int lens_count = 1;
    if (model.overlap.modelled) {
        lens_count = overlap_lenses(model, i, j, lenses, kMaxOverlapLenses);
        if (model.sampling.aim) {
            // A lens whose light provably misses the pixel (its aim finds no part of the pixel
            // where that light lands) adds nothing to the sum over lenses, and its samples would
            // all be blocked: it is left out, and the others take its samples.
            int kept = 0;
            for (int s = 0; s < lens_count; ++s)
                if (aim_reaches_pixel(model, i, j, lenses[s]))
                    lenses[kept++] = lenses[s];
            lens_count = kept;
        }
        if (lens_count == 0)
            return zero_channels<N>();
    }
    SampleSums<N> sums[kMaxOverlapLenses];
    for (int s = 0; s < lens_count; ++s) {
        for (int ch = 0; ch < N; ++ch)
            sums[s].sum[ch] = sums[s].sum_sq[ch] = 0;
        sums[s].count = 0;
    }

    int batch = model.sampling.adaptive ? std::max(1, budget.min) : count;
    double value[N], variance[N];
    int n = 0;
    int passed = 0;  // samples that passed the apertures so far
    double plain[N];  // their colours without the ray weight (for lit_area_value)
    for (int ch = 0; ch < N; ++ch)
        plain[ch] = 0;
    for (;;) {
        const int stop = std::min(count, n + batch);
        for (; n < stop; ++n) {
            int slot = 0;
            const CameraSample sample = lens_sample(i, j, n, budget.pixel_count, lens_count, &slot, stream);
            const OpticsRay ray = generate_ray(model, i, j, sample, model.overlap.modelled ? &lenses[slot] : nullptr);
            Channels<N> colour = zero_channels<N>();
            if (ray.passed) {
                const Channels<N> raw = traced_plain<N>(trace, ray);
                for (int ch = 0; ch < N; ++ch) {
                    colour.v[ch] = raw.v[ch] * ray.weight;
                    plain[ch] += raw.v[ch];
                }
                ++passed;
            }
            add_sample<N>(&sums[slot], colour);
        }
        if (!model.sampling.adaptive || n >= count)
            break;
        batch = 4;
        // While every sample so far was blocked, the zero variance says nothing: a pixel at the
        // rim of a microimage can have its lit part missed by the first samples. Blocked samples
        // cost no scene ray, so go on until one passes (or samples_max says the pixel is dark).
        if (passed == 0)
            continue;
        // The variance of the plain mean, blocked samples as zeros: the pass/block noise in it keeps
        // rim pixels sampling (tried: leaving it out to the vignetting probes stopped them too early;
        // on the benchmark's plenoptic 1.0 scene that took 1.6-2x the time for the same error).
        estimate<N>(sums, lens_count, value, variance);
        const double threshold = model.sampling.thresholds[n - 1];
        if (std::fabs(variance[0]) < threshold && std::fabs(variance[1]) < threshold &&
            std::fabs(variance[2]) < threshold && std::fabs(variance[3]) < threshold)
            break;
    }
    if (lens_count == 1 && budget.pixel_count > 1 && model.lit_area)
        return lit_area_value<N>(model, i, j, n, passed, plain, trace, stream);
    if (lens_count == 1 && budget.pixel_count > 1 && passed < n && !model.sampling.aim)
        return vignetted_value<N>(model, i, j, n, passed, sums[0].sum, trace, stream);
    estimate<N>(sums, lens_count, value, variance);
    Channels<N> out;
    for (int ch = 0; ch < N; ++ch)
        out.v[ch] = value[ch];
    if (lens_count > 1)
        out.v[3] = std::min(1.0, std::max(0.0, value[3]));
    return out;
}


// Sample streams of spectral band b start at (b + 1) * kBandStreamStride, clear of the overlap
// lens slots (0 .. kMaxOverlapLenses - 1) of stream 0 and of each other.
const int kBandStreamStride = 1024;

// Which band sample 0 of pixel (i, j) goes to (an integer hash of (i, j) modulo the bands): with
// fewer samples than bands, neighbouring pixels see different bands.
inline int band_offset(int i, int j, int bands)
{
    const unsigned h = unsigned(i) * 0x9E3779B1u ^ (unsigned(j) * 0x85EBCA77u + 0x165667B1u);
    return int((h ^ (h >> 15)) % unsigned(bands));
}

// Spectral sampling (camera/spectral_bands.h): the pixel's samples shared among the bands, each
// band's share traced through the camera at its wavelength by shade_samples, as a pixel of its own
// (vignetting, lit area, overlap and adaptive stopping included) from a sample stream of its own.
// Fixed count n over N bands: sample k goes to band (k + band_offset) mod N, so each band gets
// n / N samples, give or take one. Adaptive: every band takes ceil(MIN / N) .. ceil(MAX / N)
// samples and stops by the pixel's thresholds on its own (each band's variance below the
// threshold keeps the weighted sum's below it: the weights are at most 1 and sum to 1). The value
// of channel c is (N / S) sum_b w_c(b) v_b,c over the S bands that got samples: their weighted sum
// when every band got some, and an unbiased estimate of it when fewer samples than bands leave some
// out (each band is left out of as many pixels' sets as any other); t is the mean over them. The
// white channel (C = 5) is weighted as r is (a white image is the r channel of a white world).
template <int C, class TraceFn>
Channels<C> spectral_pixel(const PlenopticCamera& model, int i, int j, TraceFn& trace)
{
    const SpectralCameras& spectral = *model.spectral;
    const int bands = int(spectral.bands.size());
    const int count = std::max(1, model.sampling.samples_max);
    const int offset = band_offset(i, j, bands);
    double sum[C];
    for (int ch = 0; ch < C; ++ch)
        sum[ch] = 0;
    int sampled = 0;
    for (int b = 0; b < bands; ++b) {
        SampleBudget budget{0, 0, count, (b + 1) * kBandStreamStride};
        if (model.sampling.adaptive) {
            budget.min = std::max(1, (model.sampling.samples_min + bands - 1) / bands);
            budget.max = std::max(1, (count + bands - 1) / bands);
        } else {
            const int first = ((b - offset) % bands + bands) % bands;  // the first sample k of band b
            budget.min = budget.max = first < count ? (count - 1 - first) / bands + 1 : 0;
        }
        if (budget.max == 0)
            continue;
        const Channels<C> v = shade_samples<C>(spectral.cameras[size_t(b)], i, j, trace, budget);
        const double* w = spectral.bands[size_t(b)].weight;
        sum[0] += w[0] * v.v[0];
        sum[1] += w[1] * v.v[1];
        sum[2] += w[2] * v.v[2];
        sum[3] += v.v[3];
        if (C == 5)
            sum[C - 1] += w[0] * v.v[C - 1];
        ++sampled;
    }
    if (sampled == 0)
        return zero_channels<C>();
    const double scale = double(bands) / sampled;
    Channels<C> out;
    out.v[0] = sum[0] * scale;
    out.v[1] = sum[1] * scale;
    out.v[2] = sum[2] * scale;
    out.v[3] = sum[3] / sampled;
    if (C == 5)
        out.v[C - 1] = sum[C - 1] * scale;
    return out;
}

// The channels of pixel (i, j) (see shade_pixel).
template <int N, class TraceFn>
Channels<N> pixel_channels(const PlenopticCamera& model, int i, int j, TraceFn& trace)
{
    if (model.spectral)
        return spectral_pixel<N>(model, i, j, trace);
    const SampleBudget budget{model.sampling.samples_min, model.sampling.samples_max,
                              std::max(1, model.sampling.samples_max), 0};
    return shade_samples<N>(model, i, j, trace, budget);
}

} // namespace detail

// Shades pixel (i, j) of a W x H image. For each sample it builds the sample, generates the ray
// and calls trace(const OpticsRay&) -> Rgbt for unblocked rays only; a blocked sample counts as
// black and opaque (0, 0, 0, t = 0). Fixed count: model.sampling.samples_max samples. Adaptive (as
// focal_blur): samples_min samples, then batches of 4, stopping once at least one sample has
// passed the apertures and the variance of the estimate is below thresholds[n-1] in every
// channel (r, g, b, t), or samples_max is reached. When some of the n samples were blocked (and the
// camera does not aim them: aimed samples, camera/aim.h, take their plain weighted mean), the
// value is detail::vignetted_value: the mean of the traced colours times the fraction of 4n
// sample points that pass (no scene ray for those). Behind a real lens with a lit-area table
// (no array, round stop) every pixel of n > 1 samples is the mean colour of its passing samples
// times its lit area from the table, averaged over a 4 x 4 grid (detail::lit_area_value). With one sample,
// the chief ray alone (weighted by the lit area at the pixel's centre).
// With overlap modelling, the samples go round the pixel's L lenses (from overlap_lenses; with
// aimed samples, less those whose light cannot reach the pixel: aim_reaches_pixel), its own lens
// first in each round and the others in an order rotated per pixel, each as sample n / L of that
// lens's own sample stream (detail::lens_sample), and the value is the sum over lenses of each
// lens's mean; with fewer samples than lenses, the other lenses' sum is scaled up by L - 1 over
// their number sampled (detail::estimate: unbiased, as the rotation is random); t is clamped to
// [0, 1]. A pixel that no
// lens reaches is black and opaque, never background. With spectral sampling, the samples are shared
// among the wavelength bands (detail::spectral_pixel).
template <class TraceFn>
Rgbt shade_pixel(const PlenopticCamera& model, int i, int j, TraceFn trace)
{
    const detail::Channels<4> c = detail::pixel_channels<4>(model, i, j, trace);
    return Rgbt{c.v[0], c.v[1], c.v[2], c.v[3]};
}

// shade_pixel, and in *white what the same samples give in a world of radiance 1: the pixel's
// white image value (white_image.h), equal to shade_pixel(model, i, j, [](...) { return {1, 1, 1,
// 1}; }).r operation for operation, when the samples do not depend on the colours traced, i.e. with
// a fixed count (model.sampling.adaptive false; adaptive stopping looks at the scene's colours).
// A render that writes its white image keeps it this way instead of tracing the camera again.
template <class TraceFn>
Rgbt shade_pixel_and_white(const PlenopticCamera& model, int i, int j, TraceFn trace, double* white)
{
    const detail::Channels<5> c = detail::pixel_channels<5>(model, i, j, trace);
    *white = c.v[4];
    return Rgbt{c.v[0], c.v[1], c.v[2], c.v[3]};
}

// Whether any of the sample points shade_pixel looks at for pixel (i, j) passes the apertures
// (the traced samples and the vignetting probes): the pixels for which it is false are those
// no light reaches (no scene needed).
inline bool pixel_receives_light(const PlenopticCamera& model, int i, int j)
{
    bool lit = false;
    shade_pixel(model, i, j, [&lit](const OpticsRay&) {
        lit = true;
        return Rgbt{0, 0, 0, 0};
    });
    return lit;
}

} // namespace plenoptic

#endif
