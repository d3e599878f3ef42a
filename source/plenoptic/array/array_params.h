// SPDX-License-Identifier: AGPL-3.0-or-later
// The microlens array's specification as the parser fills it (microlens_array { ... }) and the one
// place where a specification becomes an array with lenses of their kind (make_microlens_array).
// The camera's checks of the block live with the other parameter checks (camera/params.h).

#ifndef PLENOPTIC_ARRAY_PARAMS_H
#define PLENOPTIC_ARRAY_PARAMS_H

#include <memory>
#include <string>
#include <vector>

#include "plenoptic/array/lens_errors.h"
#include "plenoptic/array/microlens_array.h"
#include "plenoptic/array/refracting_microlens.h"
#include "plenoptic/core/lattice.h"

namespace plenoptic {

enum class MicrolensType { Pinhole, ThinLens, Refracting };

// microlens_array { ... }. `given` is false when the scene has no array (grid stays None).
struct ArrayParams {
    bool given = false;
    GridType grid = GridType::None;         // None inside a given block: no grid keyword
    bool has_pitch = false;
    double pitch_mm = 0;
    bool has_lens = false;                  // one of pinhole / focal_length / focal_lengths / lens { } was read
    MicrolensType lens = MicrolensType::Pinhole;
    int focal_length_count = 0;             // 0 = pinhole, 1 = focal_length, 3 = focal_lengths
    double focal_lengths_mm[3] = {0, 0, 0};
    RefractingShape refracting;             // lens { }: the refracting lenses' shape
    bool has_distance = false;
    double distance_mm = 0;                 // d: array -> sensor
    double rotate_deg[3] = {0, 0, 0};       // about x, then y, then z (POV-Ray's order)
    double translate_mm[3] = {0, 0, 0};     // camera frame, after the rotation
    double abbe = 0;                        // the microlenses' Abbe number V_d; 0: no dispersion
    // Manufacturing errors: errors { } (has_errors) or lens_table "file" (lens_table_file not empty).
    bool has_errors = false;
    ErrorSpec errors;
    std::string lens_table_file;
    // The table's rows, shared: camera parameters are copied often, and a table may hold a row for
    // each of hundreds of thousands of lenses.
    std::shared_ptr<const std::vector<LensTableRow>> lens_table;
    double fill_factor = 1;                 // the part of each cell that is lens
    bool mask = false;                      // the gap is opaque (a chrome mask)
    bool baffles = false;                   // walls between microimages: no cross-talk
};

// The lenses of a checked specification, of their kind.
std::shared_ptr<const Microlens> make_microlens(const ArrayParams& params);

// The array of a checked specification, its lens (0, 0) at (0, 0, array_z) before the specification's
// translation (array_z: -D, or 0 without a main lens); no array (present() false, at array_z) when
// the scene gives none.
MicrolensArray make_microlens_array(const ArrayParams& params, double array_z);

} // namespace plenoptic

#endif
