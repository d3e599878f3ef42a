// SPDX-License-Identifier: AGPL-3.0-or-later
// Manufacturing errors of a microlens array: drawn from a seed lens by lens, or read from a table.

#include "plenoptic/array/lens_errors.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cmath>
#include <sstream>

#include "plenoptic/core/format.h"
#include "plenoptic/core/json.h"
#include "plenoptic/core/sampling.h"

namespace plenoptic {

namespace {

// mix64 (core/sampling.h): SplitMix64's step and finaliser.
std::uint64_t mix(std::uint64_t x) { return mix64(x); }

std::uint64_t lens_key(LensIndex lens)
{
    return mix(std::uint64_t(lens.k) * 0x100000001b3ull ^ mix(std::uint64_t(lens.l)));
}

// The lens's stream of uniform numbers in (0, 1), a pure function of the seed and the indices.
class LensStream {
public:
    LensStream(std::int64_t seed, LensIndex lens) : state_(mix(mix(std::uint64_t(seed)) ^ lens_key(lens))) {}
    double uniform()
    {
        state_ = mix(state_);
        return (double(state_ >> 11) + 0.5) * (1.0 / 9007199254740992.0);
    }
    // A standard normal number cut at kErrorSigmas (polar Box-Muller; a pair beyond the cut is
    // drawn again, so the distribution is the normal's, truncated).
    double normal()
    {
        if (has_spare_) {
            has_spare_ = false;
            return spare_;
        }
        for (;;) {
            const double a = 2 * uniform() - 1, b = 2 * uniform() - 1;
            const double s = a * a + b * b;
            if (!(s < 1) || s == 0)
                continue;
            const double scale = std::sqrt(-2 * std::log(s) / s);
            const double x = a * scale, y = b * scale;
            if (std::fabs(x) > kErrorSigmas || std::fabs(y) > kErrorSigmas)
                continue;
            spare_ = y;
            has_spare_ = true;
            return x;
        }
    }

private:
    std::uint64_t state_;
    double spare_ = 0;
    bool has_spare_ = false;
};

std::atomic<std::uint64_t> next_id(1);

std::string trim(const std::string& s)
{
    const std::size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

// A few recently asked lenses per thread: a pixel's samples, and its neighbours', ask the same
// lenses again and again. Keyed by the errors' id so that two arrays never share an entry.
struct CacheSlot {
    std::uint64_t owner = 0;
    LensIndex lens{0, 0};
    LensError error;
};
// The cache's slots: a 16 x 16 tile of the lattice, slot (k mod 16, l mod 16), so that the lenses
// about a pixel and about the pixels beside it never share a slot (with slots chosen by a hash of
// the indices, a few neighbouring lenses did, and were drawn again and again).
const int kCacheSide = 16;
const int kCacheSlots = kCacheSide * kCacheSide;
std::size_t cache_slot(LensIndex lens)
{
    return std::size_t(std::uint64_t(lens.k) & (kCacheSide - 1)) +
           kCacheSide * std::size_t(std::uint64_t(lens.l) & (kCacheSide - 1));
}

} // namespace

Vec3 tilt_axis(double tilt_deg, double azimuth_deg)
{
    const double t = tilt_deg * (kPi / 180), a = azimuth_deg * (kPi / 180);
    if (tilt_deg == 0)
        return Vec3{0, 0, 1};
    return Vec3{std::sin(t) * std::cos(a), std::sin(t) * std::sin(a), std::cos(t)};
}

Mat3 frame_to_axis(Vec3 a)
{
    // Rodrigues' formula for the rotation about v = z x a by the angle between them:
    // R = I + [v]x + [v]x^2 / (1 + a_z), v = (-a_y, a_x, 0).
    const double c = 1 + a.z;
    const double xx = a.x * a.x / c, yy = a.y * a.y / c, xy = a.x * a.y / c;
    return Mat3{{{1 - xx, -xy, a.x}, {-xy, 1 - yy, a.y}, {-a.x, -a.y, a.z}}};
}

std::shared_ptr<const LensErrors> LensErrors::drawn(const ErrorSpec& spec)
{
    std::shared_ptr<LensErrors> errors(new LensErrors());
    errors->drawn_ = true;
    errors->spec_ = spec;
    errors->id_ = next_id++;
    errors->max_shift_mm_ = kErrorSigmas * spec.position_sd_mm * std::sqrt(2.0);
    errors->max_dz_mm_ = kErrorSigmas * spec.position_sd_z_mm;
    errors->max_focal_deviation_ = kErrorSigmas * spec.focal_sd;
    errors->max_tilt_deg_ = spec.rotation_deg;
    return errors;
}

std::shared_ptr<const LensErrors> LensErrors::tabled(const std::vector<LensTableRow>& rows, const std::string& file,
                                                     const double* type_focal_mm, int type_count)
{
    std::shared_ptr<LensErrors> errors(new LensErrors());
    errors->drawn_ = false;
    errors->file_ = file;
    errors->id_ = next_id++;
    for (const LensTableRow& row : rows) {
        LensError e = row.error;
        if (row.focal_length_mm > 0 && type_count > 0)
            e.focal_factor = row.focal_length_mm / type_focal_mm[lens_type(row.lens, type_count)];
        e.axis = tilt_axis(e.tilt_deg, e.tilt_azimuth_deg);
        errors->table_[lens_key(row.lens)] = e;
        errors->max_shift_mm_ = std::max(errors->max_shift_mm_, std::hypot(e.dx_mm, e.dy_mm));
        errors->max_dz_mm_ = std::max(errors->max_dz_mm_, std::fabs(e.dz_mm));
        errors->max_focal_deviation_ = std::max(errors->max_focal_deviation_, std::fabs(e.focal_factor - 1));
        errors->max_tilt_deg_ = std::max(errors->max_tilt_deg_, e.tilt_deg);
    }
    return errors;
}

LensError LensErrors::draw(LensIndex lens) const
{
    LensError e;
    if (!drawn_) {
        const auto found = table_.find(lens_key(lens));
        return found == table_.end() ? e : found->second;
    }
    LensStream stream(spec_.seed, lens);
    // Always the same draws in the same order, whatever is zero, so that changing one standard
    // deviation leaves the other errors of every lens as they were.
    const double nx = stream.normal(), ny = stream.normal(), nz = stream.normal(), nf = stream.normal();
    const double tilt_u = stream.uniform(), azimuth_u = stream.uniform();
    // + 0.0: a zero standard deviation gives +0, never -0.
    e.dx_mm = spec_.position_sd_mm * nx + 0.0;
    e.dy_mm = spec_.position_sd_mm * ny + 0.0;
    e.dz_mm = spec_.position_sd_z_mm * nz + 0.0;
    e.focal_factor = 1 + spec_.focal_sd * nf;
    if (spec_.rotation_deg > 0) {
        const double cos_max = std::cos(spec_.rotation_deg * (kPi / 180));
        const double cos_tilt = 1 - tilt_u * (1 - cos_max);
        e.tilt_deg = std::acos(cos_tilt) * (180 / kPi);
        e.tilt_azimuth_deg = 360 * azimuth_u;
        e.axis = tilt_axis(e.tilt_deg, e.tilt_azimuth_deg);
    }
    return e;
}

const LensError& LensErrors::at(LensIndex lens) const
{
    thread_local CacheSlot cache[kCacheSlots];
    CacheSlot& slot = cache[cache_slot(lens)];
    if (slot.owner == id_ && slot.lens == lens)
        return slot.error;
    slot.error = draw(lens);
    slot.lens = lens;
    slot.owner = id_;
    return slot.error;
}

MetadataJson LensErrors::metadata() const
{
    MetadataJson json = MetadataJson::object();
    if (drawn_) {
        json["source"] = "drawn";
        json["position_sd_mm"] = json_number(spec_.position_sd_mm);
        json["position_sd_z_mm"] = json_number(spec_.position_sd_z_mm);
        json["focal_length_sd"] = json_number(spec_.focal_sd);
        json["rotation_deg"] = json_number(spec_.rotation_deg);
        json["seed"] = spec_.seed;
        json["truncated_at_sd"] = json_number(kErrorSigmas);
    } else {
        json["source"] = "lens_table";
        json["file"] = file_;
        json["lenses"] = table_.size();
    }
    json["max_shift_mm"] = json_number(max_shift_mm_);
    json["max_dz_mm"] = json_number(max_dz_mm_);
    json["max_focal_deviation"] = json_number(max_focal_deviation_);
    json["max_tilt_deg"] = json_number(max_tilt_deg_);
    return json;
}

ParsedLensTable parse_lens_table(const std::string& text, double pitch_mm)
{
    ParsedLensTable out;
    std::istringstream lines(text);
    std::string line;
    int number = 0;
    // Column index of each field, -1 when absent.
    enum { K, L, DX, DY, DZ, F, TILT, AZIMUTH, FIELDS };
    static const char* const names[FIELDS] = {"k", "l", "dx_mm", "dy_mm", "dz_mm", "focal_length_mm", "tilt_deg",
                                              "tilt_azimuth_deg"};
    int column[FIELDS];
    for (int& c : column)
        c = -1;
    bool header = false;
    std::unordered_map<std::uint64_t, int> seen;
    auto fail = [&](int at, const std::string& message) {
        out.rows.clear();
        out.error_line = at;
        out.error = message;
        return out;
    };
    while (std::getline(lines, line)) {
        ++number;
        if (!line.empty() && line.back() == '\r')
            line.pop_back();
        const std::size_t first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#')
            continue;
        std::vector<std::string> cells;
        std::string cell;
        std::istringstream split(line);
        while (std::getline(split, cell, ','))
            cells.push_back(trim(cell));
        if (!line.empty() && line.back() == ',')
            cells.push_back("");
        if (!header) {
            for (std::size_t i = 0; i < cells.size(); ++i)
                for (int f = 0; f < FIELDS; ++f)
                    if (cells[i] == names[f])
                        column[f] = int(i);
            if (column[K] < 0 || column[L] < 0)
                return fail(number, "the first line must name the columns, k and l among them (and any of dx_mm, dy_mm, "
                                    "dz_mm, focal_length_mm, tilt_deg, tilt_azimuth_deg)");
            header = true;
            continue;
        }
        double value[FIELDS] = {0, 0, 0, 0, 0, 0, 0, 0};
        for (int f = 0; f < FIELDS; ++f) {
            if (column[f] < 0 || std::size_t(column[f]) >= cells.size() || cells[column[f]].empty()) {
                if (f == K || f == L)
                    return fail(number, std::string("column ") + names[f] + " is empty: every row needs the lens's k and l");
                continue;
            }
            const std::string& s = cells[column[f]];
            char* end = nullptr;
            value[f] = std::strtod(s.c_str(), &end);
            if (end == s.c_str() || *end != '\0' || !std::isfinite(value[f]))
                return fail(number, std::string("column ") + names[f] + " holds \"" + s + "\", not a finite number");
            if (f == F && !(value[f] > 0))
                return fail(number, "focal_length_mm must be positive (or empty: the lens type's), got " + s);
        }
        if (value[K] != std::floor(value[K]) || value[L] != std::floor(value[L]) || std::fabs(value[K]) > 1e9 ||
            std::fabs(value[L]) > 1e9)
            return fail(number, "k and l must be whole numbers (the lens's row-form indices)");
        LensTableRow row;
        row.lens = LensIndex{std::int64_t(value[K]), std::int64_t(value[L])};
        row.error.dx_mm = value[DX];
        row.error.dy_mm = value[DY];
        row.error.dz_mm = value[DZ];
        row.focal_length_mm = value[F];
        row.error.tilt_deg = value[TILT];
        row.error.tilt_azimuth_deg = value[AZIMUTH];
        const double quarter = 0.25 * pitch_mm;
        if (!(std::fabs(value[DX]) < quarter) || !(std::fabs(value[DY]) < quarter) || !(std::fabs(value[DZ]) < quarter))
            return fail(number, "dx_mm, dy_mm and dz_mm must each be smaller than a quarter of the pitch (" +
                                    format_number(quarter) + " mm) in magnitude");
        if (!(value[F] >= 0))
            return fail(number, "focal_length_mm must be positive (or empty: the lens type's)");
        if (!(value[TILT] >= 0 && value[TILT] < 30))
            return fail(number, "tilt_deg must be in [0, 30) degrees");
        const std::uint64_t key = lens_key(row.lens);
        const auto again = seen.find(key);
        if (again != seen.end())
            return fail(number, "lens (" + std::to_string(row.lens.k) + ", " + std::to_string(row.lens.l) +
                                    ") is given twice (first on line " + std::to_string(again->second) + ")");
        seen[key] = number;
        out.rows.push_back(row);
    }
    if (!header)
        return fail(1, "the table is empty: a header line naming k, l and the error columns, then one row per lens");
    return out;
}

} // namespace plenoptic
