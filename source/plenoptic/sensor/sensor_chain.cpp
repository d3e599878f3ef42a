// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor model (see the header). The distributions are Boost.Random's (Poisson: inversion
// below a mean of 10, Hörmann's transformed rejection above; normal: the ziggurat), driven by a
// SplitMix64 stream whose state is a hash of (seed, pixel, channel, purpose).

#include "plenoptic/sensor/sensor_chain.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <vector>

#include <boost/random/normal_distribution.hpp>
#include <boost/random/poisson_distribution.hpp>

#include "plenoptic/core/format.h"
#include "plenoptic/core/json.h"
#include "plenoptic/core/threads.h"

namespace plenoptic {

namespace {

// What a random stream is for.
enum Purpose : std::uint64_t { kShot = 1, kRead = 2, kPrnu = 3, kDsnu = 4 };

// The fixed pattern (PRNU, DSNU) belongs to the sensor, not to the frame: its streams are keyed by
// this constant instead of the seed, so frames of different seeds share it, as a real sensor's
// frames do, and averaging frames leaves it.
const std::uint64_t kSensorKey = 0x706c656e6f707469ULL;

std::uint64_t mix(std::uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

// SplitMix64 (Steele, Lea and Flood 2014) as a UniformRandomBitGenerator.
class Stream {
public:
    typedef std::uint64_t result_type;
    Stream(std::uint64_t seed, std::uint64_t pixel, int channel, Purpose purpose)
        : state_(mix(mix(mix(seed + 0x9e3779b97f4a7c15ULL) ^ pixel) ^ (std::uint64_t(channel) << 8 | purpose)))
    {
    }
    static constexpr result_type min() { return 0; }
    static constexpr result_type max() { return std::numeric_limits<result_type>::max(); }
    result_type operator()()
    {
        state_ += 0x9e3779b97f4a7c15ULL;
        return mix(state_);
    }

private:
    std::uint64_t state_;
};

double standard_normal(Stream& stream)
{
    boost::random::normal_distribution<double> normal(0.0, 1.0);
    return normal(stream);
}

} // namespace

const char* bayer_name(BayerPattern pattern)
{
    switch (pattern) {
    case BayerPattern::RGGB: return "rggb";
    case BayerPattern::BGGR: return "bggr";
    case BayerPattern::GRBG: return "grbg";
    case BayerPattern::GBRG: return "gbrg";
    case BayerPattern::None: break;
    }
    return "none";
}

std::string check_bit_depth(const char* keyword, double value)
{
    if (!(value >= 1 && value <= 16 && value == std::floor(value)))
        return std::string(keyword) + " must be a whole number of bits from 1 to 16 (the raw is a 16-bit PNG), got " +
               format_number(value);
    return "";
}

std::string check_electrons(const char* keyword, double value)
{
    if (!(value > 0) || !std::isfinite(value) || value > 1e15)
        return std::string(keyword) + " must be a positive number of electrons, at most 1e15, got " + format_number(value);
    return "";
}

std::string check_non_negative(const char* keyword, double value)
{
    if (!(value >= 0) || !std::isfinite(value) || value > 1e15)
        return std::string(keyword) + " must be a number from 0 to 1e15, got " + format_number(value);
    return "";
}

std::string check_whole_number(const char* keyword, double value)
{
    if (!(value >= 0 && value <= 9007199254740992.0 && value == std::floor(value)))
        return std::string(keyword) + " must be a whole number from 0 to 2^53, got " + format_number(value);
    return "";
}

std::string check_dn(const char* keyword, double value)
{
    if (!(value >= 0 && value <= 65535 && value == std::floor(value)))
        return std::string(keyword) + " must be a whole number of DN from 0 to 65535, got " + format_number(value);
    return "";
}

std::string check_sensor_chain(const SensorChainParams& c)
{
    if (c.bit_depth < 1 || c.bit_depth > 16)
        return "sensor: bit_depth must be a whole number from 1 to 16 (the raw is a 16-bit PNG), got " +
               format_number(c.bit_depth);
    if (!(c.full_well_e > 0) || !std::isfinite(c.full_well_e))
        return "sensor: full_well must be a positive number of electrons, got " + format_number(c.full_well_e);
    const double maximum_dn = std::ldexp(1.0, c.bit_depth) - 1;
    if (c.black_level_dn < 0 || c.black_level_dn >= maximum_dn)
        return "sensor: black_level must be a whole number of DN from 0 to " + format_number(maximum_dn - 1) +
               " (below the largest value of bit_depth " + format_number(c.bit_depth) + "), got " +
               format_number(c.black_level_dn);
    return "";
}

int bayer_channel(BayerPattern pattern, int i, int j)
{
    // Channels of the 2 x 2 cell: top-left, top-right, bottom-left, bottom-right.
    static const int cells[5][4] = {{1, 1, 1, 1}, {0, 1, 1, 2}, {2, 1, 1, 0}, {1, 0, 2, 1}, {1, 2, 0, 1}};
    return cells[int(pattern)][(j & 1) * 2 + (i & 1)];
}

std::uint16_t sensor_dn(const SensorChainParams& c, double value, std::uint64_t pixel, int channel)
{
    const double mean = exposure_electrons(c) * std::max(0.0, value) + c.dark_current_e_per_s * c.exposure_time_s;
    double electrons = 0;
    if (mean > 0) {
        Stream shot(c.seed, pixel, channel, kShot);
        // Past 2^52 electrons a double no longer holds whole numbers; no well is that deep.
        const double capped = std::min(mean, 1e15);
        boost::random::poisson_distribution<std::int64_t, double> poisson(capped);
        electrons = double(poisson(shot));
    }
    if (c.prnu > 0) {
        Stream fixed(kSensorKey, pixel, channel, kPrnu);
        electrons *= 1 + c.prnu * standard_normal(fixed);
    }
    if (c.dsnu_e > 0) {
        Stream fixed(kSensorKey, pixel, channel, kDsnu);
        electrons += c.dsnu_e * standard_normal(fixed);
    }
    if (c.read_noise_e > 0) {
        Stream read(c.seed, pixel, channel, kRead);
        electrons += c.read_noise_e * standard_normal(read);
    }
    electrons = std::min(electrons, c.full_well_e);
    const double maximum_dn = std::ldexp(1.0, c.bit_depth) - 1;
    const double dn = c.black_level_dn + std::round(electrons * (maximum_dn - c.black_level_dn) / c.full_well_e);
    return std::uint16_t(std::min(maximum_dn, std::max(0.0, dn)));
}

void sensor_raw_rows(const SensorChainParams& c, const float* linear, int W, int first_row, int rows, std::uint16_t* raw,
                     int threads)
{
    const bool mosaic = c.bayer != BayerPattern::None;
    auto read_row = [&](int r) {
        const int j = first_row + r;
        const float* from = linear + size_t(r) * W * 3;
        std::uint16_t* to = raw + size_t(r) * W * (mosaic ? 1 : 3);
        for (int i = 0; i < W; ++i) {
            const std::uint64_t pixel = std::uint64_t(j) * W + i;
            const float* rgb = from + size_t(i) * 3;
            if (mosaic) {
                const int ch = bayer_channel(c.bayer, i, j);
                to[i] = sensor_dn(c, rgb[ch], pixel, ch);
            } else {
                for (int ch = 0; ch < 3; ++ch)
                    to[size_t(i) * 3 + ch] = sensor_dn(c, rgb[ch], pixel, ch);
            }
        }
    };
    std::atomic<int> next(0);
    run_on_threads(thread_count(threads, std::size_t(std::max(rows, 0))), [&](int) {
        for (int r = next++; r < rows; r = next++)
            read_row(r);
    });
}

std::vector<std::uint16_t> sensor_raw(const SensorChainParams& c, const std::vector<float>& linear, int W, int H)
{
    const bool mosaic = c.bayer != BayerPattern::None;
    std::vector<std::uint16_t> raw(size_t(W) * H * (mosaic ? 1 : 3));
    if (W > 0 && H > 0)
        sensor_raw_rows(c, linear.data(), W, 0, H, raw.data());
    return raw;
}

MetadataJson read_out_metadata(const SensorChainParams& c, const std::string& raw_file)
{
    if (!c.given)
        return MetadataJson(nullptr);
    MetadataJson out = MetadataJson::object();
    out["raw_file"] = raw_file.empty() ? MetadataJson(nullptr) : MetadataJson(raw_file);
    out["bayer"] = c.bayer == BayerPattern::None ? MetadataJson(nullptr) : MetadataJson(bayer_name(c.bayer));
    out["bit_depth"] = c.bit_depth;
    out["full_well_e"] = json_number(c.full_well_e);
    out["exposure_e"] = json_number(exposure_electrons(c));
    out["read_noise_e"] = json_number(c.read_noise_e);
    out["dark_current_e_per_s"] = json_number(c.dark_current_e_per_s);
    out["exposure_time_s"] = json_number(c.exposure_time_s);
    out["prnu"] = json_number(c.prnu);
    out["dsnu_e"] = json_number(c.dsnu_e);
    out["black_level_dn"] = c.black_level_dn;
    out["seed"] = c.seed;
    const double maximum_dn = std::ldexp(1.0, c.bit_depth) - 1;
    out["gain_dn_per_e"] = json_number((maximum_dn - c.black_level_dn) / c.full_well_e);
    out["chain"] = "signal = Poisson(exposure_e * value + dark_current_e_per_s * exposure_time_s); "
                   "e = min(signal * (1 + prnu * g) + dsnu_e * h + read_noise_e * n, full_well_e), g and h fixed per "
                   "site for the seed, n new per frame, all N(0, 1); DN = clamp(black_level_dn + round(e * "
                   "gain_dn_per_e), 0, 2^bit_depth - 1)";
    return out;
}

} // namespace plenoptic
