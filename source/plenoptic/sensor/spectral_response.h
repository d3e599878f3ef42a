// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor's spectral sensitivities: how strongly its R, G and B pixels respond to light of a
// wavelength. Spectral sampling (camera/spectral.h) traces each camera sample at one wavelength
// band and weighs the scene's RGB colour by these curves averaged over the band. Two forms:
// Gaussian bands (a centre and a full width at half maximum per channel), or a table read from a
// file (wavelength, r, g, b per row, linear between rows). Pure, no POV-Ray dependency.

#ifndef PLENOPTIC_SPECTRAL_RESPONSE_H
#define PLENOPTIC_SPECTRAL_RESPONSE_H

#include <string>
#include <vector>

#include "plenoptic/core/json.h"

namespace plenoptic {

// The wavelengths spectral sampling covers (nm): those glass.h checks every medium over.
const double kSpectralMinNm = 380;
const double kSpectralMaxNm = 720;
// Most bands `spectral N` may ask for (one per nm at most would be 340).
const int kMaxSpectralBands = 64;

// The default Gaussian bands: centred where `diffraction wavelengths` puts the channels by
// default, 90 nm wide at half maximum (the order of a Bayer sensor's colour filters). A stand-in,
// not any one camera's curve: a study of a camera gives its own (response_file).
const double kDefaultResponseCentresNm[3] = {610, 550, 465};
const double kDefaultResponseWidthsNm[3] = {90, 90, 90};
// Widths accepted for Gaussian bands (nm, full width at half maximum).
const double kMinResponseWidthNm = 1;
const double kMaxResponseWidthNm = 1000;

// One row of a tabulated response.
struct ResponseRow {
    double wavelength_nm;
    double rgb[3];
};

struct SpectralResponse {
    bool tabulated = false;
    double centre_nm[3] = {kDefaultResponseCentresNm[0], kDefaultResponseCentresNm[1], kDefaultResponseCentresNm[2]};
    double fwhm_nm[3] = {kDefaultResponseWidthsNm[0], kDefaultResponseWidthsNm[1], kDefaultResponseWidthsNm[2]};
    std::vector<ResponseRow> table;  // tabulated: rows in increasing wavelength
    std::string file;                // tabulated: the file's name as the scene wrote it

    // The sensitivity of channel c (0 R, 1 G, 2 B) at a wavelength (nm): a Gaussian of peak 1, or
    // the table's value interpolated linearly (0 outside the table).
    double at(int channel, double wavelength_nm) const;
    // Its mean over [from_nm, to_nm] (midpoint rule on 0.25 nm steps, exact to far below the
    // weights' use for smooth curves; a table's kinks cost at most one step's error).
    double mean(int channel, double from_nm, double to_nm) const;
    // The mean wavelength of channel c's curve over kSpectralMinNm..kSpectralMaxNm, weighed by the
    // curve (0.25 nm steps).
    double centroid_nm(int channel) const;
    // The metadata's description of the curves.
    MetadataJson metadata() const;
};

// Reads a tabulated response: CSV text, one row per wavelength: wavelength_nm, r, g, b (commas or
// white space between them); `#` starts a comment, blank lines are skipped, and a first line whose
// first field is not a number is a header. Rows in strictly increasing wavelength, every value
// finite, sensitivities >= 0, at least two rows, the rows spanning kSpectralMinNm..kSpectralMaxNm.
// *error: "" when read, else the reason with its 1-based line (*error_line, 0: the whole file).
SpectralResponse parse_response_table(const std::string& text, std::string* error, int* error_line);

// "" when a response can weigh spectral samples, else why not: a Gaussian centre outside 100 to
// 20000 nm or a width outside kMinResponseWidthNm..kMaxResponseWidthNm; a channel that responds to
// no wavelength of kSpectralMinNm..kSpectralMaxNm (its mean over that range is below 1e-6 of its
// peak there, so the channel could never be normalised).
std::string check_response(const SpectralResponse& response);

// "" when N is a whole number from 1 to kMaxSpectralBands, else the message.
std::string check_spectral_bands(double value);

} // namespace plenoptic

#endif
