// SPDX-License-Identifier: AGPL-3.0-or-later
// Diffraction: the Airy pattern of the aperture that forms the sensor's image,
// one wavelength per colour channel, as a convolution of the rendered picture.
//
// With an array the aperture is a microlens's, of diameter p (the cell's inscribed circle) at d
// from the sensor: every point of a microimage is spread by the Airy pattern of radius
// 1.22 lambda d / p (the first dark ring), which is 1.22 lambda N for a plenoptic 1.0 camera's
// f/N microlenses. Without an array it is the main lens's exit pupil, of diameter 2a at h from the
// sensor: 1.22 lambda h / (2a). The pattern does not change across the sensor (an ideal,
// aberration-free aperture, in focus or not), so diffracting the geometric picture is convolving
// it with the pattern integrated over a pixel: that is what a sensor point jittered by the
// pattern would see, computed without noise. The main lens's diffraction behind an array spreads
// light across the array's plane, 1.22 lambda D / A there; it is written to the metadata and not
// applied (a few percent of a pitch in practical cameras; docs/sensor.md).

#ifndef PLENOPTIC_DIFFRACTION_H
#define PLENOPTIC_DIFFRACTION_H

#include <functional>
#include <string>
#include <vector>

#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// Wavelengths accepted (nm): near ultraviolet to thermal infrared.
const double kMinWavelengthNm = 100;
const double kMaxWavelengthNm = 20000;
std::string check_wavelength(double nm);

// "" when diffraction suits the camera: it needs an aperture with a size (thin-lens microlenses,
// or without an array a main lens with an aperture), else the message.
std::string check_diffraction(const DiffractionParams& diffraction, const CameraParams& params);

// The largest Airy radius accepted, in pixels: a (8 r + 1)^2 window of 16,641 pixels at 16.
const double kMaxAiryRadiusPx = 16;

// "" when the model's Airy pattern (diffraction_of) fits kMaxAiryRadiusPx in every channel, else
// the message (the radius, and what to change).
std::string check_diffraction_size(const PlenopticCamera& model, const DiffractionParams& params);

// What the picture is convolved with.
struct Diffraction {
    bool applied = false;
    const char* aperture = "";         // "microlens" or "main_lens"
    double aperture_diameter_mm = 0;   // p, or the exit pupil's 2a
    double distance_mm = 0;            // d, or h
    double airy_radius_mm[3] = {0, 0, 0};
    // Behind an array: the main lens's Airy radius in the array's plane (not applied), per channel.
    double main_lens_airy_radius_at_array_mm[3] = {0, 0, 0};
};

Diffraction diffraction_of(const PlenopticCamera& model, const DiffractionParams& params);

// The Airy pattern (2 J1(x) / x)^2 with its first zero at `radius` (any unit), at distance r.
double airy_intensity(double r, double radius);

// The pattern of Airy radius (rx, ry) pixels (rx = radius / pixel width, ry = radius / pixel
// height) integrated over each pixel of a (2 kx + 1) x (2 ky + 1) window, kx = ceil(kRings rx),
// and normalised to sum 1 (the tail beyond is folded in, so the picture's light is kept).
const double kAiryKernelRadii = 4;  // the window's half-width in Airy radii: 96 % of the light
struct AiryKernel {
    int kx = 0, ky = 0;
    std::vector<double> weights;  // row-major, (2 ky + 1) rows of (2 kx + 1)
    double at(int dx, int dy) const { return weights[size_t((dy + ky) * (2 * kx + 1) + (dx + kx))]; }
};
AiryKernel airy_kernel(double rx_px, double ry_px);

// Convolves channel c of the interleaved W x H x `channels` picture with `kernels[c]` (outside
// the picture counts as black: light from beyond its edge is not known), in place: out(i, j) =
// sum over the window of weight(dx, dy) x picture(i - dx, j + dy). The convolution is done by
// FFTW's discrete Fourier transforms in double precision, tile by tile (tiles of a few hundred
// pixels with a margin of the kernel's half-width, bands of one tile's height): the result is the
// direct sum's within float rounding, negative rounding noise set to 0, and the memory beyond
// the picture is two bands, not a copy of it. Tiles are shared among `threads` threads (0: every
// hardware thread); the result does not depend on their number. Returns false when `cancelled`
// says so; the picture is then partly convolved and must be discarded.
bool convolve_channels(std::vector<float>& picture, int W, int H, int channels, const AiryKernel* kernels,
                       const std::function<bool()>& cancelled, int threads = 0);

// The same convolution with the picture's rows read and written through callbacks, so that the
// picture need not be in memory as a whole (memory: two bands of a tile's height and the
// kernel's margin). read(first, count, to) puts rows first .. first + count - 1 (W `channels`
// values each) at `to`; every row is read once, from the top down. write(first, count, from)
// takes the convolved rows, from the top down, each row after every row it depends on has been
// read (so the picture may be convolved in place). Either returning false stops the convolution
// (false is returned; what was written is partly convolved).
typedef std::function<bool(int first, int count, float* to)> RowReader;
typedef std::function<bool(int first, int count, const float* from)> RowWriter;
bool convolve_rows(int W, int H, int channels, const AiryKernel* kernels, const RowReader& read, const RowWriter& write,
                   const std::function<bool()>& cancelled, int threads = 0);

// The output tile's side the convolution aims at (pixels; the transforms are this plus twice the
// kernel's half-width, rounded up to a size with factors 2, 3, 5 and 7 only).
const int kConvolutionTile = 448;

// The kernels of the model's three channels for its pixel size.
std::vector<AiryKernel> channel_kernels(const PlenopticCamera& model, const Diffraction& diffraction);

} // namespace plenoptic

#endif
