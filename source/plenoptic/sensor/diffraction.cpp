// SPDX-License-Identifier: AGPL-3.0-or-later
// The Airy pattern and its convolution with the picture (see the header).

#include "plenoptic/sensor/diffraction.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

#include <boost/math/special_functions/bessel.hpp>

#include "plenoptic/camera/rays.h"

namespace plenoptic {

namespace {

const double kFirstZero = 3.8317059702075125;  // of J1: the first dark ring at x = 3.8317

} // namespace

std::string check_wavelength(double nm)
{
    if (!std::isfinite(nm))
        return "diffraction wavelengths must be finite numbers (nanometres), got " + format_number(nm);
    if (!(nm >= kMinWavelengthNm && nm <= kMaxWavelengthNm))
        return "diffraction wavelengths are in nanometres, from " + format_number(kMinWavelengthNm) + " to " +
               format_number(kMaxWavelengthNm) + ", got " + format_number(nm);
    return "";
}

std::string check_diffraction(const DiffractionParams& diffraction, const CameraParams& params)
{
    if (!diffraction.given)
        return "";
    if (params.array.given && !make_microlens(params.array)->forms_image())
        return "diffraction needs apertures with a size: pinhole microlenses have none (a point diffracts light "
               "everywhere); give the array focal_length";
    if (!params.array.given && is_pinhole(params.main))
        return "diffraction needs an aperture with a size: a pinhole main lens has none; use a thin_lens";
    return "";
}

Diffraction diffraction_of(const PlenopticCamera& m, const DiffractionParams& params)
{
    Diffraction out;
    if (!params.given)
        return out;
    if (m.array.grid != GridType::None) {
        if (!m.array.microlens->forms_image())
            return out;  // a pinhole has no aperture with a size
        out.aperture = "microlens";
        // The lens part of the cell (fill_factor): a copy of the cell scaled by sqrt(F).
        out.aperture_diameter_mm = 2 * m.array.cell_inradius_mm * m.array.aperture_scale;
        out.distance_mm = effective_array_distance_mm(m);
    } else {
        if (!m.lens || !(m.lens->exit_pupil_radius() > 0))
            return out;
        out.aperture = "main_lens";
        out.aperture_diameter_mm = 2 * m.lens->exit_pupil_radius();
        out.distance_mm = m.lens->exit_pupil_centre().z - m.sensor.z_mm;
    }
    out.applied = true;
    for (int c = 0; c < 3; ++c) {
        const double lambda_mm = params.wavelengths_nm[c] * 1e-6;
        out.airy_radius_mm[c] = 1.22 * lambda_mm * out.distance_mm / out.aperture_diameter_mm;
        if (m.array.grid != GridType::None && m.lens && m.lens->exit_pupil_radius() > 0)
            out.main_lens_airy_radius_at_array_mm[c] =
                1.22 * lambda_mm * effective_main_distance_mm(m) / (2 * m.lens->exit_pupil_radius());
    }
    return out;
}

std::string check_diffraction_size(const PlenopticCamera& m, const DiffractionParams& params)
{
    const Diffraction d = diffraction_of(m, params);
    if (!d.applied)
        return "";
    double largest = 0;
    for (int c = 0; c < 3; ++c)
        largest = std::max(largest, d.airy_radius_mm[c] / std::min(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1]));
    if (largest <= kMaxAiryRadiusPx)
        return "";
    return "diffraction would spread light over an Airy radius of " + format_number(largest) + " pixels (1.22 x " +
           "wavelength x " + format_number(d.distance_mm) + " mm / " + format_number(d.aperture_diameter_mm) +
           " mm), more than " + format_number(kMaxAiryRadiusPx) + ": the convolution would take hours; use larger "
           "pixels, a wider aperture or shorter wavelengths, or leave diffraction off";
}

double airy_intensity(double r, double radius)
{
    const double x = kFirstZero * r / radius;
    if (x < 1e-8)
        return 1;
    const double a = 2 * boost::math::cyl_bessel_j(1, x) / x;
    return a * a;
}

AiryKernel airy_kernel(double rx, double ry)
{
    AiryKernel k;
    k.kx = std::max(1, int(std::ceil(kAiryKernelRadii * rx)));
    k.ky = std::max(1, int(std::ceil(kAiryKernelRadii * ry)));
    const int w = 2 * k.kx + 1, h = 2 * k.ky + 1;
    k.weights.assign(size_t(w) * h, 0.0);
    // Midpoint points per pixel side: enough to resolve the core of a pattern narrower than a pixel
    // (compared as a double first: a pattern far narrower than a pixel asks for more than an int holds).
    const double wanted = std::ceil(12 / std::min(rx, ry));
    const int n = wanted < 24 ? std::max(4, int(wanted)) : 24;
    double total = 0;
    for (int dy = -k.ky; dy <= k.ky; ++dy)
        for (int dx = -k.kx; dx <= k.kx; ++dx) {
            double sum = 0;
            for (int b = 0; b < n; ++b)
                for (int a = 0; a < n; ++a) {
                    // In units of the Airy radius: x / rx, y / ry.
                    const double u = (dx - 0.5 + (a + 0.5) / n) / rx, v = (dy - 0.5 + (b + 0.5) / n) / ry;
                    if (u * u + v * v > kAiryKernelRadii * kAiryKernelRadii)
                        continue;
                    sum += airy_intensity(std::sqrt(u * u + v * v), 1.0);
                }
            k.weights[size_t((dy + k.ky) * w + (dx + k.kx))] = sum;
            total += sum;
        }
    if (!(total > 0)) {
        // The whole pattern lies between the midpoints of the centre pixel (an Airy radius below about
        // 0.007 pixel, where its 4 radii fall short of the nearest midpoint at 1/48 pixel on each axis):
        // all its light falls on that pixel.
        k.weights[size_t(k.ky * w + k.kx)] = total = 1;
    }
    for (double& weight : k.weights)
        weight /= total;
    return k;
}

std::vector<AiryKernel> channel_kernels(const PlenopticCamera& m, const Diffraction& d)
{
    std::vector<AiryKernel> kernels;
    for (int c = 0; c < 3; ++c)
        kernels.push_back(airy_kernel(d.airy_radius_mm[c] / m.sensor.pixel_size_mm[0], d.airy_radius_mm[c] / m.sensor.pixel_size_mm[1]));
    return kernels;
}

bool convolve_channels(std::vector<float>& picture, int W, int H, int channels, const AiryKernel* kernels,
                       const std::function<bool()>& cancelled, int threads)
{
    const std::vector<float> source(picture);
    std::atomic<int> next_row(0);
    std::atomic<bool> stop(false);
    auto work = [&]() {
        for (int j = next_row++; j < H && !stop; j = next_row++) {
            if (cancelled && cancelled()) {
                stop = true;
                return;
            }
            for (int c = 0; c < channels; ++c) {
                const AiryKernel& k = kernels[c];
                const int w = 2 * k.kx + 1;
                for (int i = 0; i < W; ++i) {
                    double sum = 0;
                    for (int dy = std::max(-k.ky, -j); dy <= std::min(k.ky, H - 1 - j); ++dy) {
                        const float* row = &source[(size_t(j + dy) * W) * channels + c];
                        const double* weights = &k.weights[size_t((dy + k.ky) * w + k.kx)];
                        // The source pixel i - dx sends light to i through weight(dx).
                        for (int dx = std::max(-k.kx, i - (W - 1)); dx <= std::min(k.kx, i); ++dx)
                            sum += weights[dx] * row[size_t(i - dx) * channels];
                    }
                    picture[(size_t(j) * W + i) * channels + c] = float(sum);
                }
            }
        }
    };
    const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
    const int count = std::max(1, std::min(threads > 0 ? threads : int(hardware), H));
    std::vector<std::thread> pool;
    for (int t = 1; t < count; ++t)
        pool.emplace_back(work);
    work();
    for (std::thread& t : pool)
        t.join();
    if (stop) {
        picture = source;
        return false;
    }
    return true;
}

} // namespace plenoptic
