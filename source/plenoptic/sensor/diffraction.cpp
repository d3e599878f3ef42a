// SPDX-License-Identifier: AGPL-3.0-or-later
// The Airy pattern and its convolution with the picture (see the header).

#include "plenoptic/sensor/diffraction.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>

#include <boost/math/special_functions/bessel.hpp>
#include <fftw3.h>

#include "plenoptic/camera/rays.h"
#include "plenoptic/core/threads.h"

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

namespace {

// FFTW's planner is not thread-safe (its plans' execution is): plans are made and destroyed under
// this lock.
std::mutex& fftw_planner()
{
    static std::mutex lock;
    return lock;
}

// The smallest size from n whose only prime factors are 2, 3, 5 and 7 (FFTW's fast sizes).
int fast_fft_size(int n)
{
    for (int m = std::max(1, n);; ++m) {
        int rest = m;
        for (int f : {2, 3, 5, 7})
            while (rest % f == 0)
                rest /= f;
        if (rest == 1)
            return m;
    }
}

// Memory FFTW aligns for its vector code; freed by fftw_free.
struct FftwDeleter {
    void operator()(void* p) const { fftw_free(p); }
};
using RealBuffer = std::unique_ptr<double, FftwDeleter>;
using SpectrumBuffer = std::unique_ptr<fftw_complex, FftwDeleter>;
RealBuffer real_buffer(size_t n) { return RealBuffer(static_cast<double*>(fftw_malloc(sizeof(double) * n))); }
SpectrumBuffer spectrum_buffer(size_t n) { return SpectrumBuffer(static_cast<fftw_complex*>(fftw_malloc(sizeof(fftw_complex) * n))); }

// One transform size's forward and inverse plans (FFTW_ESTIMATE: the same plan, so the same
// arithmetic, on every run), executed on any buffers from real_buffer / spectrum_buffer.
class TilePlans {
public:
    TilePlans(int nx, int ny) : nx_(nx), ny_(ny)
    {
        RealBuffer real = real_buffer(size_t(nx) * ny);
        SpectrumBuffer spectrum = spectrum_buffer(spectrum_size());
        std::lock_guard<std::mutex> lock(fftw_planner());
        forward_ = fftw_plan_dft_r2c_2d(ny, nx, real.get(), spectrum.get(), FFTW_ESTIMATE);
        inverse_ = fftw_plan_dft_c2r_2d(ny, nx, spectrum.get(), real.get(), FFTW_ESTIMATE);
    }
    ~TilePlans()
    {
        std::lock_guard<std::mutex> lock(fftw_planner());
        fftw_destroy_plan(forward_);
        fftw_destroy_plan(inverse_);
    }
    TilePlans(const TilePlans&) = delete;
    TilePlans& operator=(const TilePlans&) = delete;

    size_t spectrum_size() const { return size_t(ny_) * (nx_ / 2 + 1); }
    void forward(double* real, fftw_complex* spectrum) const { fftw_execute_dft_r2c(forward_, real, spectrum); }
    // Destroys `spectrum`.
    void inverse(fftw_complex* spectrum, double* real) const { fftw_execute_dft_c2r(inverse_, spectrum, real); }

private:
    int nx_, ny_;
    fftw_plan forward_ = nullptr, inverse_ = nullptr;
};

// The spectrum of `kernel` laid out for a circular convolution of size nx x ny, divided by nx ny
// (FFTW's transforms are unnormalised). The sum's row offset dy is a correlation (the source row
// j + dy), so the kernel's rows are mirrored: convolving with w(dx, -dy).
SpectrumBuffer kernel_spectrum(const AiryKernel& kernel, int nx, int ny, const TilePlans& plans)
{
    RealBuffer real = real_buffer(size_t(nx) * ny);
    std::fill(real.get(), real.get() + size_t(nx) * ny, 0.0);
    const double norm = 1.0 / (double(nx) * ny);
    for (int dy = -kernel.ky; dy <= kernel.ky; ++dy)
        for (int dx = -kernel.kx; dx <= kernel.kx; ++dx)
            real.get()[size_t((-dy + ny) % ny) * nx + size_t((dx + nx) % nx)] = kernel.at(dx, dy) * norm;
    SpectrumBuffer spectrum = spectrum_buffer(plans.spectrum_size());
    plans.forward(real.get(), spectrum.get());
    return spectrum;
}

} // namespace

bool convolve_channels(std::vector<float>& picture, int W, int H, int channels, const AiryKernel* kernels,
                       const std::function<bool()>& cancelled, int threads)
{
    const size_t row = size_t(std::max(0, W)) * std::max(0, channels);
    return convolve_rows(
        W, H, channels, kernels,
        [&](int first, int count, float* to) {
            std::copy(picture.data() + size_t(first) * row, picture.data() + size_t(first + count) * row, to);
            return true;
        },
        [&](int first, int count, const float* from) {
            std::copy(from, from + size_t(count) * row, picture.data() + size_t(first) * row);
            return true;
        },
        cancelled, threads);
}

bool convolve_rows(int W, int H, int channels, const AiryKernel* kernels, const RowReader& read, const RowWriter& write,
                   const std::function<bool()>& cancelled, int threads)
{
    if (W <= 0 || H <= 0 || channels <= 0)
        return true;
    // The margin every tile reads beyond its output: the widest kernel's half-width.
    int KX = 0, KY = 0;
    for (int c = 0; c < channels; ++c) {
        KX = std::max(KX, kernels[c].kx);
        KY = std::max(KY, kernels[c].ky);
    }
    const int nx = fast_fft_size(std::min(W, kConvolutionTile) + 2 * KX);
    const int ny = fast_fft_size(std::min(H, kConvolutionTile) + 2 * KY);
    const int tx = nx - 2 * KX, ty = ny - 2 * KY;  // a tile's output
    const TilePlans plans(nx, ny);
    std::vector<SpectrumBuffer> spectra;
    for (int c = 0; c < channels; ++c)
        spectra.push_back(kernel_spectrum(kernels[c], nx, ny, plans));

    // The source rows a band of ty output rows from j0 reads, j0 - KY to j0 + ty + KY (black
    // beyond the picture), and the band's output, written back once the band is done: the rows
    // the next band reads above its own are the last 2 KY of this band's source.
    const size_t row = size_t(W) * channels;
    std::vector<float> source(size_t(ny) * row, 0.0f), output(size_t(ty) * row, 0.0f);
    // Rows first_row .. first_row + count - 1 into the source from its row first_local: the
    // picture's through `read` (each once, from the top down), black beyond it.
    auto load_rows = [&](int first_local, int first_row, int count) {
        const int lo = std::max(0, first_row), hi = std::min(H, first_row + count);
        float* to = &source[size_t(first_local) * row];
        std::fill(to, to + size_t(count) * row, 0.0f);
        return hi <= lo || read(lo, hi - lo, to + size_t(lo - first_row) * row);
    };

    const int tiles = (W + tx - 1) / tx;
    const int tasks = tiles * channels;
    const int count = thread_count(threads, std::size_t(std::max(tasks, 0)));
    // Each thread's own transform buffers.
    struct Scratch {
        RealBuffer real;
        SpectrumBuffer spectrum;
    };
    std::vector<Scratch> scratch;
    for (int t = 0; t < count; ++t)
        scratch.push_back(Scratch{real_buffer(size_t(nx) * ny), spectrum_buffer(plans.spectrum_size())});

    auto convolve_tile = [&](int task, Scratch& s) {
        const int tile = task / channels, c = task % channels;
        const int i0 = tile * tx;
        double* real = s.real.get();
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) {
                const int i = i0 - KX + x;
                real[size_t(y) * nx + x] = (i >= 0 && i < W) ? double(source[size_t(y) * row + size_t(i) * channels + c]) : 0.0;
            }
        plans.forward(real, s.spectrum.get());
        const fftw_complex* k = spectra[size_t(c)].get();
        fftw_complex* f = s.spectrum.get();
        for (size_t n = 0; n < plans.spectrum_size(); ++n) {
            const double re = f[n][0] * k[n][0] - f[n][1] * k[n][1];
            const double im = f[n][0] * k[n][1] + f[n][1] * k[n][0];
            f[n][0] = re;
            f[n][1] = im;
        }
        plans.inverse(f, real);
        const int width = std::min(tx, W - i0);
        for (int r = 0; r < ty; ++r)
            for (int q = 0; q < width; ++q)
                // Light is never negative: what the transforms' rounding leaves below 0 is 0.
                output[size_t(r) * row + size_t(i0 + q) * channels + c] =
                    float(std::max(0.0, real[size_t(r + KY) * nx + size_t(q + KX)]));
    };

    for (int j0 = 0; j0 < H; j0 += ty) {
        if (j0 == 0) {
            if (!load_rows(0, -KY, ny))
                return false;
        } else {
            std::copy(&source[size_t(ty) * row], &source[size_t(ny) * row], &source[0]);
            if (!load_rows(2 * KY, j0 + KY, ty))
                return false;
        }
        std::atomic<int> next(0);
        std::atomic<bool> stop(false);
        // Each thread with its own buffers; the calling thread (t = 0) looks at `cancelled` between
        // its tiles.
        run_on_threads(count, [&](int t) {
            for (int task = next++; task < tasks && !stop; task = next++) {
                if (t == 0 && cancelled && cancelled()) {
                    stop = true;
                    break;
                }
                convolve_tile(task, scratch[size_t(t)]);
            }
        });
        if (stop)
            return false;
        if (!write(j0, std::min(ty, H - j0), output.data()))
            return false;
    }
    return true;
}

} // namespace plenoptic
