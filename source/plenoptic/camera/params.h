// SPDX-License-Identifier: AGPL-3.0-or-later
// Parameters of the plenoptic camera as the parser fills them, and the checks that refuse bad input.

#ifndef PLENOPTIC_PARAMS_H
#define PLENOPTIC_PARAMS_H

#include <string>

#include "plenoptic/array/array_params.h"
#include "plenoptic/core/format.h"
#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/spectral_bands.h"
#include "plenoptic/lens/main_lens_params.h"
#include "plenoptic/sensor/sensor_chain.h"

namespace plenoptic {

// What a pixel's value measures (camera/radiometry.h): Flat, the radiance times the share of
// the sampled aperture that passes (the first phase's camera, equal to the stock cameras); or
// Irradiance, the sensor irradiance with its cos^4 law, normalised so that an on-axis pixel of
// the camera without an array sees radiance L as L.
enum class Radiometry { Flat, Irradiance };

// Defaults for keywords the user may omit.
const double kDefaultMmPerUnit = 1000.0;     // one scene unit is one metre
const double kDefaultPixelSizeMm = 0.01;
const double kDefaultSensorOffsetMm = 0.0;
// Rays per pixel when `samples` is omitted, chosen from the speed/accuracy curve (BENCHMARKS.md):
// 16 where a lens aperture must be sampled (thin-lens microlenses; a thin main lens without an
// array): one ray would show no defocus blur at all, and 16 is the smallest count that gives
// about 30 dB PSNR there. 1 where each point of a pixel has a single ray through pinholes, as
// the stock perspective camera without antialiasing. default_samples() applies the rule.
const int kDefaultSamplesApertures = 16;
const int kDefaultSamplesPinholes = 1;
// SamplingParams::samples when the scene does not give `samples`.
const int kSamplesOmitted = 0;
const double kDefaultConfidence = 0.9;       // as focal_blur
const double kDefaultVariance = 1.0 / 128.0; // as focal_blur
// Upper bound of `samples`: keeps every count an int and a render finite.
const int kMaxSamples = 1000000;
// Every length of the optics lies in this range (mm). Outside it, products and
// squares of lengths would leave double precision.
const double kMinLengthMm = 1e-12;
const double kMaxLengthMm = 1e12;

// Largest exponent of `angular_response`: cos^64 of 10 degrees is 0.38, a pixel blind beyond 20.
const double kMaxAngularExponent = 64;

struct SensorParams {
    double pixel_size_mm[2] = {kDefaultPixelSizeMm, kDefaultPixelSizeMm};
    double offset_mm[2] = {kDefaultSensorOffsetMm, kDefaultSensorOffsetMm};
    // `angular_response n`: a pixel's response to light arriving at angle t to the sensor's normal
    // is cos^n(t), as on-chip microlenses make it (irradiance radiometry only; 0: none).
    double angular_exponent = 0;
    SensorChainParams chain;  // the raw's read-out (sensor/sensor_chain.h); chain.given: write it
};

// `samples N` gives adaptive = false and samples = N.
// `samples MIN, MAX [confidence C] [variance V]` gives adaptive = true.
struct SamplingParams {
    int samples = kSamplesOmitted;          // kSamplesOmitted: default_samples() of the camera
    bool adaptive = false;
    int samples_min = 0;
    int samples_max = 0;
    double confidence = kDefaultConfidence;
    double variance = kDefaultVariance;
};

// `diffraction [on | off] [wavelengths <r, g, b>]` (nanometres; sensor/diffraction.h).
struct DiffractionParams {
    bool given = false;
    // Centres of common colour filters' pass bands: red 610, green 550, blue 465 nm.
    double wavelengths_nm[3] = {610, 550, 465};
};

struct CameraParams {
    double mm_per_unit = kDefaultMmPerUnit;
    Radiometry radiometry = Radiometry::Flat;  // `radiometry flat | irradiance`
    DiffractionParams diffraction;
    MainLensParams main;
    ArrayParams array;
    SensorParams sensor;
    SamplingParams sampling;
    SpectralParams spectral;  // `spectral N` (camera/spectral_bands.h); bands 0: off
};

// The camera's parameters with the main lens at f-number N (aperture from N, as `f_number N`).
CameraParams at_f_number(const CameraParams& params, double f_number);

// ---- Per-value checks, called by the parser while the token is current. ----
// Each returns "" when the value is fine, else a complete message naming the keyword,
// the value and the valid range.

std::string check_finite(const char* keyword, double value);
std::string check_positive_length(const char* keyword, double value_mm);  // pitch, focal_length, ...
std::string check_f_number(double value);
std::string check_mm_per_unit(double value);
std::string check_focus_distance(double value_units);
std::string check_angle(const char* keyword, double degrees);             // rotate components
std::string check_translation(const char* keyword, double value_mm);      // translate, offset
std::string check_samples(const char* keyword, double value);             // a whole number 1..kMaxSamples
std::string check_adaptive_minimum(double value);                           // samples MIN, MAX: MIN >= 2
std::string check_confidence(double value);
std::string check_blades(double value);                                     // a whole number 3..kMaxBlades
std::string check_variance(double value);
std::string check_angular_exponent(double value);                          // 0 .. kMaxAngularExponent
std::string check_error_deviation(const char* keyword, double value);      // errors position, focal_length: >= 0
std::string check_error_rotation(double degrees);                           // errors rotation: [0, 30)
std::string check_fill_factor(double value);                                // (0, 1]

// ---- Cross-field checks, run when a block's closing brace is read. ----
std::string check_main_lens(const MainLensParams& main, double mm_per_unit);
// Part of check_main_lens for a real lens (traced or thick_lens) with f_number or aperture: the
// stop so sized must be the aperture that limits the axial beam to the array (or sensor), else the
// lens cannot deliver it (the message names the keyword, its value, the limiting surface, the
// fastest f-number the lens reaches and the largest useful stop). "" when it can, or when another
// check of check_main_lens refuses the lens first.
std::string check_aperture_reach(const MainLensParams& main, double mm_per_unit);
// Where a surface was written, for messages: "surface 9 (line 46 of lens_file \"x.dat\")" or
// "surface 3 (scene line 12)"; the stop is "the stop (surface 7, ...)".
std::string describe_surface(const Prescription& lens, int index, const std::string& lens_file);
// A positive number to 4 significant digits, rounded up (round_up) or down, for messages that
// suggest a value to type.
std::string format_rounded(double value, bool round_up);
std::string check_array(const ArrayParams& array);
// Part of check_array: manufacturing errors, fill factor and mask.
std::string check_array_errors(const ArrayParams& array);
// microlens_array lens { }: the glass's index (1 < n <= kMaxMicrolensIor) and the cap's conic
// constant (kMinMicrolensConic to kMaxMicrolensConic), at their keywords; the shape against the
// array's cell (the cap covers its cell, is no taller than its thickness) in check_array.
const double kMaxMicrolensIor = 4;
const double kMinMicrolensConic = -100, kMaxMicrolensConic = 100;
std::string check_microlens_ior(const char* keyword, double value);
std::string check_microlens_conic(const char* keyword, double value);
std::string check_refracting_shape(const ArrayParams& array);
std::string check_sensor(const SensorParams& sensor);
std::string check_sampling(const SamplingParams& sampling);
// spectral N with its response (camera/spectral_bands.h): "" when off or usable.
std::string check_spectral(const SpectralParams& spectral);
// The whole camera, run when the camera's closing brace is read. Runs the block checks again
// (cheap), then the checks that need several blocks at once.
std::string check_camera(const CameraParams& camera);

// The camera's placement as POV-Ray resolved it (right, up, direction in the scene, any length):
// each must have a finite, non-zero length, and together they must span 3-D space (unit
// vectors whose triple product is at least 1e-9 in magnitude, the rule the metadata reader
// applies too). Empty when the placement is usable.
std::string check_placement(const double right[3], const double up[3], const double direction[3]);

// Rays per pixel for a camera whose scene omits `samples` (see kDefaultSamplesApertures).
int default_samples(const CameraParams& camera);


} // namespace plenoptic

#endif
