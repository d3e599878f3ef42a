// SPDX-License-Identifier: AGPL-3.0-or-later
// Spectral sampling's bands: `spectral N` splits the traced wavelengths (380 to 720 nm) into N
// bands of equal width. Each camera sample is traced at one band's centre wavelength through every
// dispersing element, and the scene's RGB colour it brings is weighed, channel by channel, by the
// sensor's sensitivity over that band (sensor/spectral_response.h), normalised over the bands:
//   w_c(b) = S_c(b) / sum_b' S_c(b'),   S_c(b) the mean of channel c's curve over band b,
// so that a channel's weights sum to 1. A pixel's value is then sum_b w_c(b) v_b,c, v_b the
// pixel's value traced at band b (camera/pixel.h): through a lens that does not disperse every
// v_b has one expectation, which the pixel keeps, as without `spectral`. Pure, no POV-Ray
// dependency.

#ifndef PLENOPTIC_SPECTRAL_BANDS_H
#define PLENOPTIC_SPECTRAL_BANDS_H

#include <vector>

#include "plenoptic/core/json.h"
#include "plenoptic/sensor/spectral_response.h"

namespace plenoptic {

// `spectral N` with its response; bands 0: no spectral sampling.
struct SpectralParams {
    int bands = 0;
    SpectralResponse response;
    bool gaussian_written = false;  // response_centres or response_widths was written
    bool given() const { return bands > 0; }
};

struct SpectralBand {
    double from_nm, to_nm;   // the band
    double wavelength_nm;    // its centre, where its samples are traced
    double weight[3];        // w_c(b) for R, G, B
};

// The N bands of equal width over kSpectralMinNm..kSpectralMaxNm with their weights; empty when
// spectral sampling is off. The response must have passed check_response.
std::vector<SpectralBand> spectral_bands(const SpectralParams& params);

// A channel's wavelength under spectral sampling: the mean of the bands' centres weighed by the
// channel's weights (where its ground truth per channel is computed).
double channel_wavelength_nm(const std::vector<SpectralBand>& bands, int channel);

// The wavelengths at which ground truth per channel is computed (R, G, B): with spectral sampling
// channel_wavelength_nm of its bands (where the render's light of that channel comes from); without
// it, the centroids of the default response's curves (SpectralResponse::centroid_nm), the limit of
// many bands. The one place that says which wavelength a channel is.
void channel_wavelengths_nm(const SpectralParams& params, double out[3]);

// The metadata's spectral section: bands, their wavelengths, the channels' weights and
// wavelengths, the response.
MetadataJson spectral_metadata(const SpectralParams& params);

} // namespace plenoptic

#endif
