// SPDX-License-Identifier: AGPL-3.0-or-later
// libFuzzer target over the plenoptic camera's parameter validation and ray generation.
//
// The input bytes decode into a CameraParams (every field, including extreme doubles, NaN and
// infinities, flags and enums in any combination), an image size, a few pixels, a sample count
// and a 3-D point. Every check_* function runs on the values. For every parameter set that
// check_camera accepts, the model is built and these invariants must hold (else abort()):
//   - every value the accepted camera uses is finite, and the model's planes are finite and ordered;
//   - every unblocked sample of the chosen pixels gives a finite, unit direction into the scene
//     (+z), starting on the plane of the last element (main-lens plane z = 0 inside the aperture;
//     the pinhole itself; the posed array plane without a main lens);
//   - the chief ray is finite and unit; shade_pixel is finite (small sample counts);
//   - forward_project of the point gives finite pixel positions inside the image;
//   - the metadata JSON holds no NaN or infinity.
//
// Byte format (fuzz/make_corpus.py writes the same): fields in the order of decode() below; a
// double is a tag byte then: tag%4 == 0 -> kSpecials[next byte % count]; 1 -> 8 raw bytes
// (little-endian IEEE); 2 -> int16 mantissa * 10^(int8 exponent); 3 -> int8 value. An int is a tag
// byte then: tag%3 == 0 -> int8; 1 -> 4 raw bytes; 2 -> kIntSpecials[next % count]. Flags and
// enums are one byte each. Missing bytes read as zero.
//
// Built with clang -fsanitize=fuzzer,address,undefined by fuzz/CMakeLists.txt; replayed over the
// seed corpus with the ordinary compiler by tests/robustness (fuzz/replay_main.cpp).

#include <algorithm>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/truth/metadata.h"
#include "plenoptic/optics.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/camera/pixel.h"
#include "plenoptic/core/sampling.h"
#include "plenoptic/sensor/sensor_chain.h"

namespace {

using namespace plenoptic;

// The kind of a model's main lens, as the metadata names it ("none" without one).
inline std::string lens_kind(const PlenopticCamera& m) { return m.lens ? m.lens->kind_name() : "none"; }

const double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

const double kSpecials[] = {
    0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 16.0, 50.0, 0.01, 0.08, 0.32, 1000.0,
    1e-12, 1 + 1e-12, 1 - 1e-12, 1e-9, 1e-6, 1e6, 1e9, 1e12, 1e-300, 1e300,
    DBL_MIN, DBL_MIN / 4 /* subnormal */, DBL_MAX, -DBL_MAX, DBL_EPSILON,
    kInf, -kInf, kNaN, -kNaN, 45.0, 89.99, 90.0, 180.0, 360.0, 1e-9 /* degrees */, -89.99,
    0.999999, 0.9, 1.5, 1.0 / 128, 2.5, 52.3, 12.5,
};
const int kIntSpecials[] = {0, 1, -1, 2, 4, 16, 64, kMaxSamples, kMaxSamples + 1, INT_MAX, INT_MIN, 3, 1000};

struct Reader {
    Reader(const uint8_t* d, size_t n) : data(d), size(n), pos(0) {}
    const uint8_t* data;
    size_t size;
    size_t pos;
    uint8_t byte() { return pos < size ? data[pos++] : 0; }
    bool flag() { return byte() & 1; }
    double real()
    {
        const uint8_t tag = byte();
        switch (tag % 4) {
        case 0:
            return kSpecials[byte() % (sizeof kSpecials / sizeof kSpecials[0])];
        case 1: {
            uint64_t bits = 0;
            for (int i = 0; i < 8; ++i)
                bits |= uint64_t(byte()) << (8 * i);
            double value;
            std::memcpy(&value, &bits, sizeof value);
            return value;
        }
        case 2: {
            const int16_t mantissa = int16_t(uint16_t(byte()) | uint16_t(byte()) << 8);
            const int8_t exponent = int8_t(byte());
            return double(mantissa) * std::pow(10.0, double(exponent));
        }
        default:
            return double(int8_t(byte()));
        }
    }
    int integer()
    {
        const uint8_t tag = byte();
        switch (tag % 3) {
        case 0:
            return int8_t(byte());
        case 1: {
            uint32_t bits = 0;
            for (int i = 0; i < 4; ++i)
                bits |= uint32_t(byte()) << (8 * i);
            int32_t value;
            std::memcpy(&value, &bits, sizeof value);
            return value;
        }
        default:
            return kIntSpecials[byte() % (sizeof kIntSpecials / sizeof kIntSpecials[0])];
        }
    }
};

struct Input {
    CameraParams params;
    int W = 1, H = 1;
    int pixel_count = 1;
    int pixels[4][2] = {};
    int samples = 1;
    double point[3] = {0, 0, 1};
    double pixel_value = 0;  // a noise-free value for the sensor's read-out, anything a picture may hold
};

Input decode(const uint8_t* data, size_t size)
{
    Reader r(data, size);
    Input in;
    CameraParams& p = in.params;
    p.mm_per_unit = r.real();

    MainLensParams& m = p.main;
    m.given = r.flag();
    m.type = MainLensType(r.byte() % 3);
    m.has_focal_length = r.flag();
    m.focal_length_mm = r.real();
    m.has_f_number = r.flag();
    m.f_number = r.real();
    m.has_aperture = r.flag();
    m.aperture_mm = r.real();
    m.has_focus_distance = r.flag();
    m.focus_distance_units = r.real();
    m.has_distance = r.flag();
    m.distance_mm = r.real();

    ArrayParams& a = p.array;
    a.given = r.flag();
    a.grid = GridType(r.byte() % 3);
    a.has_pitch = r.flag();
    a.pitch_mm = r.real();
    a.has_lens = r.flag();
    a.lens = MicrolensType(r.byte() % 2);
    a.focal_length_count = r.byte() % 4;
    for (double& f : a.focal_lengths_mm)
        f = r.real();
    a.has_distance = r.flag();
    a.distance_mm = r.real();
    for (double& v : a.rotate_deg)
        v = r.real();
    for (double& v : a.translate_mm)
        v = r.real();

    for (double& v : p.sensor.pixel_size_mm)
        v = r.real();
    for (double& v : p.sensor.offset_mm)
        v = r.real();

    SamplingParams& s = p.sampling;
    s.samples = r.integer();
    s.adaptive = r.flag();
    s.samples_min = r.integer();
    s.samples_max = r.integer();
    s.confidence = r.real();
    s.variance = r.real();

    in.W = 1 + r.byte() % 48;
    in.H = 1 + r.byte() % 48;
    in.pixel_count = 1 + r.byte() % 4;
    for (int k = 0; k < in.pixel_count; ++k) {
        in.pixels[k][0] = r.byte() % in.W;
        in.pixels[k][1] = r.byte() % in.H;
    }
    in.samples = 1 + r.byte() % 8;
    for (double& v : in.point)
        v = r.real();

    // The sensor's read-out (appended: inputs written before it decode as before, without one).
    SensorChainParams& c = p.sensor.chain;
    c.given = r.flag();
    c.bayer = BayerPattern(r.byte() % 5);
    c.bit_depth = r.integer();
    c.full_well_e = r.real();
    c.has_exposure = r.flag();
    c.exposure_e = r.real();
    c.read_noise_e = r.real();
    c.dark_current_e_per_s = r.real();
    c.exposure_time_s = r.real();
    c.prnu = r.real();
    c.dsnu_e = r.real();
    c.black_level_dn = r.integer();
    c.seed = std::uint64_t(r.integer());
    in.pixel_value = r.real();
    // Radiometry and diffraction (appended likewise).
    p.radiometry = r.flag() ? Radiometry::Irradiance : Radiometry::Flat;
    p.diffraction.given = r.flag();
    for (double& v : p.diffraction.wavelengths_nm)
        v = r.real();
    return in;
}

const char* name(MainLensType t) { return t == MainLensType::None ? "none" : t == MainLensType::Pinhole ? "pinhole" : "thin_lens"; }
const char* name(GridType t) { return t == GridType::None ? "none" : t == GridType::Rectangular ? "rectangular" : "hexagonal"; }

void dump(const Input& in)
{
    const CameraParams& p = in.params;
    const MainLensParams& m = p.main;
    const ArrayParams& a = p.array;
    std::fprintf(stderr,
                 "  mm_per_unit %.17g radiometry %s angular_response %.17g\n"
                 "  main_lens given %d type %s  focal_length %d:%.17g f_number %d:%.17g aperture %d:%.17g "
                 "focus_distance %d:%.17g distance %d:%.17g\n"
                 "  microlens_array given %d grid %s pitch %d:%.17g lens %s count %d f <%.17g, %.17g, %.17g> "
                 "distance %d:%.17g rotate <%.17g, %.17g, %.17g> translate <%.17g, %.17g, %.17g>\n"
                 "  sensor pixel_size <%.17g, %.17g> offset <%.17g, %.17g>\n"
                 "  samples %d adaptive %d min %d max %d confidence %.17g variance %.17g\n"
                 "  image %dx%d, %d samples, point <%.17g, %.17g, %.17g>\n",
                 p.mm_per_unit, p.radiometry == Radiometry::Irradiance ? "irradiance" : "flat",
                 p.sensor.angular_exponent, m.given, name(m.type), m.has_focal_length, m.focal_length_mm, m.has_f_number,
                 m.f_number, m.has_aperture, m.aperture_mm, m.has_focus_distance, m.focus_distance_units,
                 m.has_distance, m.distance_mm, a.given, name(a.grid), a.has_pitch, a.pitch_mm,
                 a.lens == MicrolensType::Pinhole ? "pinhole" : "thin_lens", a.focal_length_count,
                 a.focal_lengths_mm[0], a.focal_lengths_mm[1], a.focal_lengths_mm[2], a.has_distance, a.distance_mm,
                 a.rotate_deg[0], a.rotate_deg[1], a.rotate_deg[2], a.translate_mm[0], a.translate_mm[1],
                 a.translate_mm[2], p.sensor.pixel_size_mm[0], p.sensor.pixel_size_mm[1], p.sensor.offset_mm[0],
                 p.sensor.offset_mm[1], p.sampling.samples, p.sampling.adaptive, p.sampling.samples_min,
                 p.sampling.samples_max, p.sampling.confidence, p.sampling.variance, in.W, in.H, in.samples,
                 in.point[0], in.point[1], in.point[2]);
}

const Input* g_input = nullptr;

#define FUZZ_ASSERT(cond, ...)                                                    \
    do {                                                                          \
        if (!(cond)) {                                                            \
            std::fprintf(stderr, "plenoptic_fuzz: invariant failed: %s\n  ", #cond); \
            std::fprintf(stderr, __VA_ARGS__);                                    \
            std::fprintf(stderr, "\n");                                           \
            if (g_input)                                                          \
                dump(*g_input);                                                   \
            std::abort();                                                         \
        }                                                                         \
    } while (0)

bool finite3(const double v[3]) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// The per-value checks: a NaN or an infinity is never fine; a fine value is finite.
void per_value_checks(const CameraParams& p)
{
    const double values[] = {p.mm_per_unit, p.main.focal_length_mm, p.main.f_number, p.main.aperture_mm,
                             p.main.focus_distance_units, p.main.distance_mm, p.array.pitch_mm,
                             p.array.distance_mm, p.sensor.pixel_size_mm[0], p.sensor.offset_mm[1],
                             p.sampling.confidence, p.sampling.variance, p.array.rotate_deg[0],
                             p.array.translate_mm[2]};
    for (double v : values) {
        const std::string results[] = {check_finite("x", v), check_positive_length("x", v), check_f_number(v),
                                       check_mm_per_unit(v), check_focus_distance(v), check_angle("x", v),
                                       check_translation("x", v), check_samples("x", v), check_confidence(v),
                                       check_variance(v)};
        for (const std::string& message : results)
            FUZZ_ASSERT(std::isfinite(v) || !message.empty(), "a per-value check accepted %.17g", v);
        FUZZ_ASSERT(!check_positive_length("x", v).empty() || v > 0, "positive length accepted %.17g", v);
        FUZZ_ASSERT(!check_samples("x", v).empty() || (v >= 1 && v <= kMaxSamples && v == std::floor(v)),
                    "samples accepted %.17g", v);
        FUZZ_ASSERT(!check_confidence(v).empty() || (v > 0 && v < 1), "confidence accepted %.17g", v);
        // format_number reads back exactly (or names the non-finite value).
        const std::string text = format_number(v);
        if (std::isfinite(v))
            FUZZ_ASSERT(std::strtod(text.c_str(), nullptr) == v, "format_number(%.17g) = %s", v, text.c_str());
    }
}

// What an accepted camera uses is finite and in range.
void accepted_values_are_sane(const CameraParams& p)
{
    FUZZ_ASSERT(std::isfinite(p.mm_per_unit) && p.mm_per_unit > 0, "mm_per_unit %.17g", p.mm_per_unit);
    const MainLensParams& m = p.main;
    FUZZ_ASSERT(m.given || p.array.given, "a camera with neither main lens nor array was accepted");
    if (m.given) {
        FUZZ_ASSERT(m.type != MainLensType::None, "main lens without type accepted");
        if (m.has_focal_length || m.type == MainLensType::ThinLens)
            FUZZ_ASSERT(std::isfinite(m.focal_length_mm) && m.focal_length_mm > 0, "focal_length %.17g", m.focal_length_mm);
        if (m.has_f_number)
            FUZZ_ASSERT(std::isfinite(m.f_number) && m.f_number > 0, "f_number %.17g", m.f_number);
        if (m.has_aperture)
            FUZZ_ASSERT(std::isfinite(m.aperture_mm) && m.aperture_mm > 0, "aperture %.17g", m.aperture_mm);
        if (m.has_distance)
            FUZZ_ASSERT(std::isfinite(m.distance_mm) && m.distance_mm > 0, "distance %.17g", m.distance_mm);
        if (m.has_focus_distance)
            FUZZ_ASSERT(std::isfinite(m.focus_distance_units) && m.focus_distance_units > 0, "focus %.17g",
                        m.focus_distance_units);
        FUZZ_ASSERT(!(m.has_focus_distance && m.has_distance), "both focus_distance and distance accepted");
        if (m.type == MainLensType::ThinLens)
            FUZZ_ASSERT(m.has_f_number != m.has_aperture, "f_number %d / aperture %d accepted", m.has_f_number,
                        m.has_aperture);
    }
    const ArrayParams& a = p.array;
    if (a.given) {
        FUZZ_ASSERT(a.grid != GridType::None, "array without grid accepted");
        FUZZ_ASSERT(std::isfinite(a.pitch_mm) && a.pitch_mm > 0, "pitch %.17g", a.pitch_mm);
        FUZZ_ASSERT(std::isfinite(a.distance_mm) && a.distance_mm > 0, "array distance %.17g", a.distance_mm);
        FUZZ_ASSERT(finite3(a.rotate_deg) && finite3(a.translate_mm), "pose not finite");
        if (a.lens == MicrolensType::ThinLens) {
            FUZZ_ASSERT(a.focal_length_count == 1 || a.focal_length_count == 3, "focal length count %d",
                        a.focal_length_count);
            FUZZ_ASSERT(a.focal_length_count == 1 || a.grid == GridType::Hexagonal, "focal_lengths on a rectangular grid");
            for (int i = 0; i < a.focal_length_count; ++i)
                FUZZ_ASSERT(std::isfinite(a.focal_lengths_mm[i]) && a.focal_lengths_mm[i] > 0, "microlens f %.17g",
                            a.focal_lengths_mm[i]);
        } else {
            FUZZ_ASSERT(a.focal_length_count == 0, "pinhole array with %d focal lengths", a.focal_length_count);
        }
        FUZZ_ASSERT(!(m.given && m.type == MainLensType::Pinhole && a.lens == MicrolensType::Pinhole),
                    "pinhole/pinhole accepted");
    }
    for (int i = 0; i < 2; ++i) {
        FUZZ_ASSERT(std::isfinite(p.sensor.pixel_size_mm[i]) && p.sensor.pixel_size_mm[i] > 0, "pixel size %.17g",
                    p.sensor.pixel_size_mm[i]);
        FUZZ_ASSERT(std::isfinite(p.sensor.offset_mm[i]), "offset %.17g", p.sensor.offset_mm[i]);
    }
    const SamplingParams& s = p.sampling;
    if (s.adaptive) {
        FUZZ_ASSERT(s.samples_min >= 1 && s.samples_min <= s.samples_max && s.samples_max <= kMaxSamples,
                    "adaptive %d..%d", s.samples_min, s.samples_max);
        FUZZ_ASSERT(s.confidence > 0 && s.confidence < 1 && std::isfinite(s.variance) && s.variance > 0,
                    "confidence %.17g variance %.17g", s.confidence, s.variance);
    } else {
        FUZZ_ASSERT(s.samples == kSamplesOmitted || (s.samples >= 1 && s.samples <= kMaxSamples), "samples %d",
                    s.samples);
    }
}

void model_is_sane(const PlenopticCamera& m)
{
    FUZZ_ASSERT(std::isfinite(m.sensor.z_mm) && m.sensor.z_mm < 0, "sensor plane z = %.17g", m.sensor.z_mm);
    FUZZ_ASSERT(std::isfinite(m.distance_mm), "D = %.17g", m.distance_mm);
    FUZZ_ASSERT(m.sampling.samples_min >= 1 && m.sampling.samples_min <= m.sampling.samples_max && m.sampling.samples_max <= kMaxSamples,
                "model samples %d..%d", m.sampling.samples_min, m.sampling.samples_max);
    if (lens_kind(m) == "thin_lens")
        FUZZ_ASSERT(std::isfinite(m.aperture_mm()) && m.aperture_mm() > 0 && std::isfinite(m.focal_length_mm()),
                    "aperture %.17g F %.17g", m.aperture_mm(), m.focal_length_mm());
    const Vec3 c = m.array.pose.centre_mm;
    FUZZ_ASSERT(is_finite(c) && is_finite(m.array.pose.normal), "array pose not finite");
    if (m.array.grid != GridType::None) {
        FUZZ_ASSERT(c.z > m.sensor.z_mm, "array at z %.17g not above the sensor %.17g", c.z, m.sensor.z_mm);
        if (lens_kind(m) != "none")
            FUZZ_ASSERT(c.z < 0, "array at z %.17g not behind the main lens", c.z);
    }
}

void check_ray(const PlenopticCamera& m, const OpticsRay& r, const char* what, int i, int j)
{
    const Vec3 o{r.origin_mm.x, r.origin_mm.y, r.origin_mm.z};
    const Vec3 d{r.dir.x, r.dir.y, r.dir.z};
    FUZZ_ASSERT(is_finite(o) && is_finite(d), "%s of pixel (%d, %d): origin (%g, %g, %g) dir (%g, %g, %g)", what, i, j,
                o.x, o.y, o.z, d.x, d.y, d.z);
    FUZZ_ASSERT(std::fabs(length(d) - 1) <= 1e-12, "%s of pixel (%d, %d): |dir| = %.17g", what, i, j, length(d));
    // Into the scene: +z (optics.h). A z component that rounds to zero (sensors 1e300 times
    // wider than the lens distance) is rounding, not a backward ray.
    FUZZ_ASSERT(d.z > -1e-9, "%s of pixel (%d, %d): direction (%.17g, %.17g, %.17g) points back into the camera",
                what, i, j, d.x, d.y, d.z);
}

void check_origin(const PlenopticCamera& m, const OpticsRay& r, int i, int j)
{
    const Vec3 o{r.origin_mm.x, r.origin_mm.y, r.origin_mm.z};
    if (lens_kind(m) == "pinhole") {
        FUZZ_ASSERT(o.x == 0 && o.y == 0 && o.z == 0, "pixel (%d, %d): origin (%g, %g, %g) is not the pinhole", i, j,
                    o.x, o.y, o.z);
    } else if (lens_kind(m) == "thin_lens") {
        FUZZ_ASSERT(o.z == 0, "pixel (%d, %d): origin z %.17g off the main-lens plane", i, j, o.z);
        // The origin is where the line from the sensor point crosses the lens plane: it rounds at
        // the sensor's magnitudes (a sensor offset of 1e9 mm moves it by 1e-7 mm).
        const double sensor_scale = std::fabs(m.sensor.offset_mm[0]) + std::fabs(m.sensor.offset_mm[1]) +
                                    m.sensor.film.width * m.sensor.pixel_size_mm[0] +
                                    m.sensor.film.height * m.sensor.pixel_size_mm[1] + std::fabs(m.sensor.z_mm);
        FUZZ_ASSERT(std::hypot(o.x, o.y) <= 0.5 * m.aperture_mm() * (1 + 1e-12) + 1e-15 * sensor_scale,
                    "pixel (%d, %d): origin (%g, %g) outside the aperture %.17g", i, j, o.x, o.y, m.aperture_mm());
    } else {
        const Vec3 local = mul_transposed(m.array.pose.rotation, o - m.array.pose.centre_mm);
        // Relative to the magnitudes involved: o = centre + R local rounds at |centre| and |o|.
        FUZZ_ASSERT(std::fabs(local.z) <= 1e-9 * (1 + length(o) + length(m.array.pose.centre_mm)),
                    "pixel (%d, %d): origin (%g, %g, %g) is %.3g mm off the array plane", i, j, o.x, o.y, o.z, local.z);
    }
}

// A JSON number token that is not finite (outside strings).
bool json_has_non_finite(const std::string& json)
{
    bool in_string = false;
    for (size_t k = 0; k < json.size(); ++k) {
        const char c = json[k];
        if (in_string) {
            if (c == '\\')
                ++k;
            else if (c == '"')
                in_string = false;
            continue;
        }
        if (c == '"')
            in_string = true;
        else if (json.compare(k, 3, "nan") == 0 || json.compare(k, 3, "inf") == 0 || json.compare(k, 3, "NaN") == 0 ||
                 json.compare(k, 8, "Infinity") == 0)
            return true;
    }
    return false;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const Input in = decode(data, size);
    g_input = &in;
    const CameraParams& p = in.params;
    per_value_checks(p);
    // The block checks must agree with the whole-camera check: a refused block refuses the camera.
    const std::string main_message = check_main_lens(p.main, p.mm_per_unit);
    const std::string array_message = check_array(p.array);
    const std::string sensor_message = check_sensor(p.sensor);
    const std::string sampling_message = check_sampling(p.sampling);
    const std::string message = check_camera(p);
    if (!(main_message.empty() && array_message.empty() && sensor_message.empty() && sampling_message.empty()))
        FUZZ_ASSERT(!message.empty(), "a block was refused (%s%s%s%s) but the camera accepted", main_message.c_str(),
                    array_message.c_str(), sensor_message.c_str(), sampling_message.c_str());
    if (!message.empty()) {
        g_input = nullptr;
        return 0;
    }
    accepted_values_are_sane(p);
    // Diffraction's checks (wavelengths while parsed, the aperture at the camera's brace, the
    // pattern's size once the model is built): refused inputs end here, as in the parser.
    for (double v : p.diffraction.wavelengths_nm)
        if (p.diffraction.given && !check_wavelength(v).empty()) {
            g_input = nullptr;
            return 0;
        }
    if (!check_diffraction(p.diffraction, p).empty()) {
        g_input = nullptr;
        return 0;
    }
    if (p.sensor.chain.given) {
        // The parser's per-value checks let only these through; with them, every site's DN lies in
        // range whatever the picture holds (NaN, infinities, negative or huge values).
        const SensorChainParams& c = p.sensor.chain;
        const bool values_ok = check_bit_depth("bit_depth", c.bit_depth).empty() &&
                               check_electrons("full_well", c.full_well_e).empty() &&
                               (!c.has_exposure || check_electrons("exposure", c.exposure_e).empty()) &&
                               check_non_negative("read_noise", c.read_noise_e).empty() &&
                               check_non_negative("dark_current", c.dark_current_e_per_s).empty() &&
                               check_non_negative("exposure_time", c.exposure_time_s).empty() &&
                               check_non_negative("prnu", c.prnu).empty() && check_non_negative("dsnu", c.dsnu_e).empty() &&
                               check_dn("black_level", c.black_level_dn).empty();
        if (values_ok) {
            const double maximum = std::ldexp(1.0, c.bit_depth) - 1;
            for (double v : {in.pixel_value, 0.0, 1.0, 1e300, -1.0, kNaN, kInf}) {
                const int dn = sensor_dn(c, v, 12345, 1);
                FUZZ_ASSERT(dn >= 0 && dn <= maximum, "sensor_dn(%g) = %d outside 0..%g", v, dn, maximum);
            }
        }
    }
    const PlenopticCamera m = with_film(make_camera(p), in.W, in.H);
    model_is_sane(m);
    if (check_diffraction_size(m, p.diffraction).empty()) {
        // The picture keeps its light through the convolution and stays finite.
        const Diffraction d = diffraction_of(m, p.diffraction);
        if (d.applied && in.W * in.H <= 48 * 48) {
            const std::vector<AiryKernel> kernels = channel_kernels(m, d);
            std::vector<float> picture(size_t(in.W) * in.H * 3, 0.5f);
            FUZZ_ASSERT(convolve_channels(picture, in.W, in.H, 3, kernels.data(), nullptr, 1), "convolution cancelled");
            for (float v : picture)
                FUZZ_ASSERT(std::isfinite(v) && v >= 0 && v <= 0.5f + 1e-5f, "convolved value %g", double(v));
        }
    } else {
        g_input = nullptr;
        return 0;
    }
    const std::vector<std::string> warned = warnings(m);
    for (const std::string& w : warned)
        FUZZ_ASSERT(!w.empty(), "empty warning");

    const int W = in.W, H = in.H;
    for (int k = 0; k < in.pixel_count; ++k) {
        const int i = in.pixels[k][0], j = in.pixels[k][1];
        const int count = std::max(in.samples, std::min(m.sampling.samples_max, 8));
        for (int n = 0; n < in.samples; ++n) {
            OpticsRay r;
            if ((r = m.generate_ray(i, j, make_sample(i, j, n, count))).passed) {
                check_ray(m, r, "generate_ray", i, j);
                check_origin(m, r, i, j);
            }
        }
        check_ray(m, m.chief_ray(i, j), "chief_ray", i, j);
        LensIndex lenses[kMaxOverlapLenses];
        const int lens_count = overlap_lenses(m, i, j, lenses, kMaxOverlapLenses);
        FUZZ_ASSERT(lens_count >= 0 && lens_count <= kMaxOverlapLenses, "overlap_lenses gave %d", lens_count);
        for (int l = 0; l < lens_count && l < 4; ++l) {
            OpticsRay r;
            if ((r = generate_ray(m, i, j, make_sample(i, j, l, 4), &lenses[l])).passed) {
                check_ray(m, r, "generate_ray through an overlap lens", i, j);
                check_origin(m, r, i, j);
            }
        }
        if (m.sampling.samples_max <= 16) {
            const Rgbt v = shade_pixel(m, i, j, [](const OpticsRay& r) {
                return Rgbt{r.dir.x, r.dir.y, r.dir.z, 0.5};
            });
            FUZZ_ASSERT(std::isfinite(v.r) && std::isfinite(v.g) && std::isfinite(v.b) && std::isfinite(v.t),
                        "shade_pixel (%d, %d) = (%g, %g, %g, %g)", i, j, v.r, v.g, v.b, v.t);
            // A white world: no pixel is negative or NaN, under either radiometry.
            const Rgbt white = shade_pixel(m, i, j, [](const OpticsRay&) { return Rgbt{1, 1, 1, 1}; });
            FUZZ_ASSERT(std::isfinite(white.r) && white.r >= 0, "white pixel (%d, %d) = %g", i, j, white.r);
        }
    }
    // forward_project visits every lens that can image into the picture (bounded at 2^22 lenses);
    // skip sizes where that is millions of lenses, to keep the fuzzer fast.
    const double span_mm = std::max(W * m.sensor.pixel_size_mm[0], H * m.sensor.pixel_size_mm[1]);
    if (m.array.grid == GridType::None || span_mm <= 64 * m.array.pitch_mm) {
        for (const PixelHit& hit : m.project(Vec3{in.point[0], in.point[1], in.point[2]})) {
            FUZZ_ASSERT(std::isfinite(hit.u) && std::isfinite(hit.v), "forward_project hit (%g, %g)", hit.u, hit.v);
            FUZZ_ASSERT(hit.u >= -0.5 && hit.u < W - 0.5 && hit.v >= -0.5 && hit.v < H - 0.5,
                        "forward_project hit (%.17g, %.17g) outside the %dx%d image", hit.u, hit.v, W, H);
        }
        const MicroimageLattice lattice = microimage_lattice(m);
        if (lattice.valid)
            FUZZ_ASSERT(std::isfinite(lattice.origin_px[0]) && std::isfinite(lattice.origin_px[1]),
                        "lattice origin (%g, %g)", lattice.origin_px[0], lattice.origin_px[1]);
        const CameraFrame frame = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        const std::string json = metadata_json(m, p, frame, "");
        FUZZ_ASSERT(!json_has_non_finite(json), "metadata JSON has a non-finite number:\n%s", json.c_str());
    }
    g_input = nullptr;
    return 0;
}
