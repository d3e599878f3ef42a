// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor's spectral sensitivities (spectral_response.h).

#include "plenoptic/sensor/spectral_response.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "plenoptic/core/format.h"
#include "plenoptic/sensor/diffraction.h"

namespace plenoptic {

namespace {

const char* const kChannelNames[3] = {"r", "g", "b"};

// A Gaussian's sigma from its full width at half maximum: FWHM = 2 sqrt(2 ln 2) sigma.
double sigma_of_fwhm(double fwhm) { return fwhm / (2 * std::sqrt(2 * std::log(2.0))); }

// Splits a line into fields at commas and white space.
std::vector<std::string> fields_of(const std::string& line)
{
    std::vector<std::string> out;
    std::string field;
    for (char ch : line) {
        if (ch == ',' || ch == ' ' || ch == '\t' || ch == '\r') {
            if (!field.empty())
                out.push_back(field);
            field.clear();
        } else {
            field += ch;
        }
    }
    if (!field.empty())
        out.push_back(field);
    return out;
}

// The whole field as a number (false when it is not one).
bool number_of(const std::string& field, double* value)
{
    const char* begin = field.c_str();
    char* end = nullptr;
    *value = std::strtod(begin, &end);
    return end != begin && *end == '\0';
}

} // namespace

double SpectralResponse::at(int channel, double wavelength_nm) const
{
    if (!tabulated) {
        const double z = (wavelength_nm - centre_nm[channel]) / sigma_of_fwhm(fwhm_nm[channel]);
        return std::exp(-0.5 * z * z);
    }
    if (table.empty() || wavelength_nm < table.front().wavelength_nm || wavelength_nm > table.back().wavelength_nm)
        return 0;
    // The first row at or beyond the wavelength.
    const auto after = std::lower_bound(table.begin(), table.end(), wavelength_nm,
                                        [](const ResponseRow& row, double nm) { return row.wavelength_nm < nm; });
    if (after == table.begin())
        return after->rgb[channel];
    const ResponseRow& b = *after;
    const ResponseRow& a = *(after - 1);
    const double t = (wavelength_nm - a.wavelength_nm) / (b.wavelength_nm - a.wavelength_nm);
    return a.rgb[channel] + t * (b.rgb[channel] - a.rgb[channel]);
}

double SpectralResponse::mean(int channel, double from_nm, double to_nm) const
{
    const double step = 0.25;
    const int steps = std::max(1, int(std::ceil((to_nm - from_nm) / step)));
    const double h = (to_nm - from_nm) / steps;
    double sum = 0;
    for (int k = 0; k < steps; ++k)
        sum += at(channel, from_nm + (k + 0.5) * h);
    return sum / steps;
}

double SpectralResponse::centroid_nm(int channel) const
{
    double sum = 0, weight = 0;
    for (double nm = kSpectralMinNm + 0.125; nm < kSpectralMaxNm; nm += 0.25) {
        const double w = at(channel, nm);
        sum += w * nm;
        weight += w;
    }
    return weight > 0 ? sum / weight : 0;
}

MetadataJson SpectralResponse::metadata() const
{
    MetadataJson json = MetadataJson::object();
    json["model"] = tabulated ? "table" : "gaussian";
    if (tabulated) {
        json["file"] = file;
        json["rows"] = int(table.size());
    } else {
        json["centres_nm"] = json_numbers(centre_nm, 3);
        json["fwhm_nm"] = json_numbers(fwhm_nm, 3);
    }
    return json;
}

SpectralResponse parse_response_table(const std::string& text, std::string* error, int* error_line)
{
    SpectralResponse response;
    response.tabulated = true;
    *error = "";
    *error_line = 0;
    std::istringstream in(text);
    std::string line;
    int number = 0;
    bool seen_data = false;
    while (std::getline(in, line)) {
        ++number;
        if (number == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0)
            line.erase(0, 3);  // a UTF-8 byte-order mark
        const size_t hash = line.find('#');
        if (hash != std::string::npos)
            line.erase(hash);
        const std::vector<std::string> fields = fields_of(line);
        if (fields.empty())
            continue;
        double first = 0;
        if (!seen_data && response.table.empty() && !number_of(fields[0], &first)) {
            seen_data = true;  // a header: only as the first line with fields
            continue;
        }
        seen_data = true;
        *error_line = number;
        if (fields.size() != 4) {
            *error = "a row holds 4 numbers (wavelength_nm, r, g, b), this one " + std::to_string(fields.size()) +
                     " fields";
            return response;
        }
        ResponseRow row;
        double values[4];
        for (int k = 0; k < 4; ++k) {
            if (!number_of(fields[size_t(k)], &values[k]) || !std::isfinite(values[k])) {
                *error = "field " + std::to_string(k + 1) + " (\"" + fields[size_t(k)] + "\") is not a finite number";
                return response;
            }
        }
        row.wavelength_nm = values[0];
        for (int c = 0; c < 3; ++c) {
            row.rgb[c] = values[c + 1];
            if (row.rgb[c] < 0) {
                *error = std::string("the ") + kChannelNames[c] + " sensitivity must be 0 or more, got " +
                         format_number(row.rgb[c]);
                return response;
            }
        }
        if (!response.table.empty() && !(row.wavelength_nm > response.table.back().wavelength_nm)) {
            *error = "wavelengths must increase from row to row: " + format_number(row.wavelength_nm) + " nm follows " +
                     format_number(response.table.back().wavelength_nm) + " nm";
            return response;
        }
        response.table.push_back(row);
    }
    *error_line = 0;
    if (response.table.size() < 2) {
        *error = "a response table needs at least two rows (wavelength_nm, r, g, b), it has " +
                 std::to_string(response.table.size());
        return response;
    }
    if (response.table.front().wavelength_nm > kSpectralMinNm || response.table.back().wavelength_nm < kSpectralMaxNm) {
        *error = "the table must span the traced wavelengths, " + format_number(kSpectralMinNm) + " to " +
                 format_number(kSpectralMaxNm) + " nm; it covers " + format_number(response.table.front().wavelength_nm) +
                 " to " + format_number(response.table.back().wavelength_nm) + " nm";
        return response;
    }
    return response;
}

std::string check_response(const SpectralResponse& response)
{
    if (!response.tabulated) {
        for (int c = 0; c < 3; ++c) {
            const double centre = response.centre_nm[c], width = response.fwhm_nm[c];
            if (!(centre >= kMinWavelengthNm && centre <= kMaxWavelengthNm))
                return std::string("spectral response_centres: the ") + kChannelNames[c] + " centre must be from " +
                       format_number(kMinWavelengthNm) + " to " + format_number(kMaxWavelengthNm) + " nm, got " +
                       format_number(centre);
            if (!(width >= kMinResponseWidthNm && width <= kMaxResponseWidthNm))
                return std::string("spectral response_widths: the ") + kChannelNames[c] + " width must be from " +
                       format_number(kMinResponseWidthNm) + " to " + format_number(kMaxResponseWidthNm) +
                       " nm (full width at half maximum), got " + format_number(width);
        }
    }
    for (int c = 0; c < 3; ++c) {
        double peak = 0;
        for (double nm = kSpectralMinNm; nm <= kSpectralMaxNm; nm += 0.25)
            peak = std::max(peak, response.at(c, nm));
        const double mean = response.mean(c, kSpectralMinNm, kSpectralMaxNm);
        if (!(peak > 0) || !(mean > 1e-6 * peak))
            return std::string("the spectral response's ") + kChannelNames[c] + " channel responds to no wavelength from " +
                   format_number(kSpectralMinNm) + " to " + format_number(kSpectralMaxNm) +
                   " nm, so its samples cannot be weighed";
    }
    return "";
}

std::string check_spectral_bands(double value)
{
    if (!(value >= 1 && value <= kMaxSpectralBands) || value != std::floor(value))
        return "spectral takes a whole number of wavelength bands from 1 to " + std::to_string(kMaxSpectralBands) +
               ", got " + format_number(value);
    return "";
}

} // namespace plenoptic
