// SPDX-License-Identifier: AGPL-3.0-or-later
// The sensor model: from the noise-free linear picture the camera renders to the raw
// a real sensor would read out, in digital numbers (DN), optionally through a Bayer mosaic.
//
// Per pixel and colour site, with v the noise-free value (1.0 is the exposure's reference):
//   signal  = Poisson(X v + I_dark t)                 electrons: shot noise with the dark current
//   e       = signal (1 + prnu g) + dsnu h + read n   g, h: fixed per pixel and site (the seed's
//                                                     fixed pattern), n: new per frame; N(0, 1)
//   e       = min(e, E)                               the full well clips
//   DN      = clamp(K + round(e (2^B - 1 - K) / E), 0, 2^B - 1)
// X: exposure (electrons of a pixel whose value is 1), I_dark: dark current (e-/s), t: exposure
// time (s), prnu: gain non-uniformity (relative, rms), dsnu: dark signal non-uniformity
// (electrons rms), read: read noise (electrons rms), E: full well (electrons), K: black level
// (DN), B: bit depth. Every random number comes from a counter-based generator keyed by the pixel,
// the site, what the number is for and, for the frame's noise (shot, read), the seed: the raw
// depends on the seed and the picture only, never on the order of the pixels or the thread count.
// The fixed pattern (g, h) is the sensor's: the same for every seed, so frames of several seeds
// are frames of one sensor.

#ifndef PLENOPTIC_SENSOR_CHAIN_H
#define PLENOPTIC_SENSOR_CHAIN_H

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace plenoptic {

// Which colour each site of a 2 x 2 Bayer cell records, named by its top-left, top-right,
// bottom-left and bottom-right sites (image rows from the top).
enum class BayerPattern { None, RGGB, BGGR, GRBG, GBRG };

const char* bayer_name(BayerPattern pattern);  // "rggb" ...; "none"

// sensor { bayer ... bit_depth ... } as the parser fills it. `given` is true when any of the
// chain's keywords was written: then the raw is written beside the image.
struct SensorChainParams {
    bool given = false;
    BayerPattern bayer = BayerPattern::None;
    int bit_depth = 12;
    double full_well_e = 10000;
    bool has_exposure = false;         // without `exposure`, X is the full well: a value of 1 fills it
    double exposure_e = 0;
    double read_noise_e = 0;
    double dark_current_e_per_s = 0;
    double exposure_time_s = 0;
    double prnu = 0;
    double dsnu_e = 0;
    int black_level_dn = 0;
    std::uint64_t seed = 0;
};

// Per-value checks, called by the parser while the value's keyword is current: "" when fine,
// else the whole message naming the keyword and what is allowed.
std::string check_bit_depth(const char* keyword, double value);          // a whole number 1..16
std::string check_electrons(const char* keyword, double value);          // full_well, exposure: > 0
std::string check_non_negative(const char* keyword, double value);       // read_noise, dark_current, ...
std::string check_whole_number(const char* keyword, double value);       // seed: 0..2^53
std::string check_dn(const char* keyword, double value);                 // black_level: 0..65535

// X, electrons of a pixel whose noise-free value is 1: `exposure`, or the full well without it.
inline double exposure_electrons(const SensorChainParams& c) { return c.has_exposure ? c.exposure_e : c.full_well_e; }

// "" when the chain is consistent, else the message (the block's closing brace is the place).
std::string check_sensor_chain(const SensorChainParams& chain);

// The metadata's sensor.read_out section: the chain from the noise-free picture to the raw, every
// parameter as used, the raw's file name (""; null: asked for but not written); null without a
// chain.
nlohmann::ordered_json read_out_metadata(const SensorChainParams& chain, const std::string& raw_file);

// The colour channel (0 red, 1 green, 2 blue) of pixel (i, j)'s site (i: column, j: row from the
// top), for a pattern other than None.
int bayer_channel(BayerPattern pattern, int i, int j);

// One site's DN from its noise-free value (finite, >= 0; larger values clip at the full well).
// `pixel` is the pixel's index j W + i, `channel` its colour (the fixed pattern and the noise of
// each site are its own).
std::uint16_t sensor_dn(const SensorChainParams& chain, double value, std::uint64_t pixel, int channel);

// The raw of a W x H picture (`linear`: W H 3 values, rows from the top, RGB): W H values (the
// mosaic) with a Bayer pattern, else W H 3 (every channel read out at every pixel).
std::vector<std::uint16_t> sensor_raw(const SensorChainParams& chain, const std::vector<float>& linear, int W, int H);

// The same for `rows` rows of the picture from row `first_row` (`linear`: rows W 3 values; `raw`:
// room for rows W values with a Bayer pattern, else rows W 3): the raw's values for those rows,
// equal to sensor_raw's. Rows are shared among `threads` threads (0: every hardware thread).
void sensor_raw_rows(const SensorChainParams& chain, const float* linear, int W, int first_row, int rows, std::uint16_t* raw,
                     int threads = 0);

} // namespace plenoptic

#endif
