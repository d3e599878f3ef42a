// SPDX-License-Identifier: AGPL-3.0-or-later
// Manufacturing errors of a microlens array, lens by lens: each lens displaced from its lattice
// centre (in the array's plane and along its normal), its focal length scaled, its optical axis
// tilted. Either drawn from a seed (microlens_array { errors { ... } }) or read from a table measured
// in a laboratory (lens_table "file.csv"). Answers, for any lens, its error, without storing one per
// lens: drawn errors are a pure function of the seed and the lens's indices (so every thread, every
// tile and every tool sees the same lens), tabled ones a lookup.

#ifndef PLENOPTIC_LENS_ERRORS_H
#define PLENOPTIC_LENS_ERRORS_H

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "plenoptic/core/lattice.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

// One lens's error, in the array's own frame (array/microlens_array.h: lens (0, 0) at the origin,
// +z towards the scene).
struct LensError {
    double dx_mm = 0, dy_mm = 0, dz_mm = 0;  // the lens centre's displacement from its lattice point
    double focal_factor = 1;                 // its focal length over its type's
    double tilt_deg = 0;                     // the angle between its optical axis and the array's normal
    double tilt_azimuth_deg = 0;             // towards which side it leans: from +x towards +y
    Vec3 axis = Vec3{0, 0, 1};               // its optical axis (unit), from the two angles

    bool tilted() const { return tilt_deg != 0; }
};

// errors { position S [S_z] focal_length F rotation R seed N }.
struct ErrorSpec {
    double position_sd_mm = 0;     // S: each of dx, dy
    double position_sd_z_mm = 0;   // S_z: dz
    double focal_sd = 0;           // F: the focal length is scaled by 1 + e, e of this standard deviation
    double rotation_deg = 0;       // R: the axis tilts by at most this
    std::int64_t seed = 0;
};

// Normal draws are cut at this many standard deviations (redrawn beyond it): a lens can be found
// from its lattice cell and its neighbours, and no focal length goes negative.
const double kErrorSigmas = 4;

// One row of a lens table, as read.
struct LensTableRow {
    LensIndex lens;
    LensError error;
    double focal_length_mm = 0;  // the lens's measured focal length (0: its type's)
};

struct ParsedLensTable {
    std::vector<LensTableRow> rows;
    int error_line = 0;      // > 0: the line of the error
    std::string error;       // "" when the table is fine
};

// A lens table's text: a header naming the columns (k and l needed; dx_mm, dy_mm, dz_mm,
// focal_length_mm, tilt_deg, tilt_azimuth_deg optional, any other column ignored, so that a
// microimages.csv written with errors reads back), then one row per lens; an empty cell is the
// ideal value. Refuses a lens given twice, non-finite numbers, |dx|, |dy| of a quarter pitch or
// more, tilts of 30 degrees or more, negative focal lengths.
ParsedLensTable parse_lens_table(const std::string& text, double pitch_mm);

class LensErrors {
public:
    // Drawn from a seed: dx, dy ~ N(0, S), dz ~ N(0, S_z), e ~ N(0, F) (each cut at kErrorSigmas),
    // the axis uniform over the cap of half-angle R (cos of the tilt uniform in [cos R, 1], the
    // azimuth uniform).
    static std::shared_ptr<const LensErrors> drawn(const ErrorSpec& spec);
    // Measured: the rows' lenses; every other lens is ideal. focal_length_mm of a row is turned
    // into a factor of its type's focal length by `type_focal_mm(lens)` (0 for pinholes: the column
    // is refused then).
    static std::shared_ptr<const LensErrors> tabled(const std::vector<LensTableRow>& rows, const std::string& file,
                                                    const double* type_focal_mm, int type_count);

    // The lens's error; the same for every caller, in any order, on any thread.
    const LensError& at(LensIndex lens) const;

    // Bounds over every lens: the largest in-plane displacement, |dz|, |focal factor - 1|, tilt.
    double max_shift_mm() const { return max_shift_mm_; }
    double max_dz_mm() const { return max_dz_mm_; }
    double max_focal_deviation() const { return max_focal_deviation_; }
    double max_tilt_deg() const { return max_tilt_deg_; }
    bool tilts() const { return max_tilt_deg_ > 0; }
    bool scales_focal_lengths() const { return max_focal_deviation_ > 0; }

    // The metadata's microlens_array.errors: the spec or the table, and the bounds.
    nlohmann::ordered_json metadata() const;

private:
    LensErrors() {}
    LensError draw(LensIndex lens) const;

    bool drawn_ = true;
    ErrorSpec spec_;
    std::string file_;
    std::unordered_map<std::uint64_t, LensError> table_;
    std::uint64_t id_ = 0;  // tells this object's cached lenses from another's
    double max_shift_mm_ = 0, max_dz_mm_ = 0, max_focal_deviation_ = 0, max_tilt_deg_ = 0;
};

// The axis for a tilt and its azimuth (degrees): (sin t cos a, sin t sin a, cos t).
Vec3 tilt_axis(double tilt_deg, double azimuth_deg);

// The rotation taking +z to `axis` about the axis z x axis (the identity for +z): a lens's own
// frame (its cell in the plane z = 0, its axis +z) to the array's.
Mat3 frame_to_axis(Vec3 axis);

} // namespace plenoptic

#endif
