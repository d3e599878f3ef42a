// SPDX-License-Identifier: AGPL-3.0-or-later
// Spectral sampling's bands and weights (spectral_bands.h).

#include "plenoptic/camera/spectral_bands.h"

namespace plenoptic {

std::vector<SpectralBand> spectral_bands(const SpectralParams& params)
{
    std::vector<SpectralBand> bands;
    if (!params.given())
        return bands;
    const int n = params.bands;
    const double width = (kSpectralMaxNm - kSpectralMinNm) / n;
    double total[3] = {0, 0, 0};
    for (int b = 0; b < n; ++b) {
        SpectralBand band;
        band.from_nm = kSpectralMinNm + b * width;
        band.to_nm = b + 1 == n ? kSpectralMaxNm : kSpectralMinNm + (b + 1) * width;
        band.wavelength_nm = 0.5 * (band.from_nm + band.to_nm);
        for (int c = 0; c < 3; ++c) {
            band.weight[c] = params.response.mean(c, band.from_nm, band.to_nm);
            total[c] += band.weight[c];
        }
        bands.push_back(band);
    }
    for (SpectralBand& band : bands)
        for (int c = 0; c < 3; ++c)
            band.weight[c] /= total[c];
    return bands;
}

double channel_wavelength_nm(const std::vector<SpectralBand>& bands, int channel)
{
    double sum = 0, weight = 0;
    for (const SpectralBand& band : bands) {
        sum += band.weight[channel] * band.wavelength_nm;
        weight += band.weight[channel];
    }
    return weight > 0 ? sum / weight : 0;
}

void channel_wavelengths_nm(const SpectralParams& params, double out[3])
{
    if (params.given()) {
        const std::vector<SpectralBand> bands = spectral_bands(params);
        for (int c = 0; c < 3; ++c)
            out[c] = channel_wavelength_nm(bands, c);
        return;
    }
    const SpectralResponse response;
    for (int c = 0; c < 3; ++c)
        out[c] = response.centroid_nm(c);
}

MetadataJson spectral_metadata(const SpectralParams& params)
{
    const std::vector<SpectralBand> bands = spectral_bands(params);
    MetadataJson json = MetadataJson::object();
    json["bands"] = int(bands.size());
    MetadataJson centres = MetadataJson::array();
    MetadataJson weights[3] = {MetadataJson::array(), MetadataJson::array(), MetadataJson::array()};
    for (const SpectralBand& band : bands) {
        centres.push_back(json_number(band.wavelength_nm));
        for (int c = 0; c < 3; ++c)
            weights[c].push_back(json_number(band.weight[c]));
    }
    json["range_nm"] = MetadataJson::array({json_number(kSpectralMinNm), json_number(kSpectralMaxNm)});
    json["wavelengths_nm"] = centres;
    MetadataJson channel_weights = MetadataJson::object();
    const char* names[3] = {"r", "g", "b"};
    double channel_nm[3];
    for (int c = 0; c < 3; ++c) {
        channel_weights[names[c]] = weights[c];
        channel_nm[c] = channel_wavelength_nm(bands, c);
    }
    json["weights"] = channel_weights;
    json["channel_wavelengths_nm"] = json_numbers(channel_nm, 3);
    json["response"] = params.response.metadata();
    return json;
}

} // namespace plenoptic
