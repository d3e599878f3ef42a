// SPDX-License-Identifier: AGPL-3.0-or-later
// From the array's specification to the array.

#include "plenoptic/array/array_params.h"

#include <cmath>
#include <vector>

namespace plenoptic {

std::shared_ptr<const Microlens> make_microlens(const ArrayParams& params)
{
    switch (params.lens) {
    case MicrolensType::ThinLens:
        return make_thin_microlens(params.focal_lengths_mm, params.focal_length_count == 3 ? 3 : 1);
    case MicrolensType::Refracting:
        return make_refracting_microlens(params.refracting);
    case MicrolensType::Pinhole:
        break;
    }
    return make_pinhole_microlens();
}

MicrolensArray make_microlens_array(const ArrayParams& params, double array_z)
{
    if (!params.given || params.grid == GridType::None)
        return no_microlens_array(array_z);
    const Vec3 centre{params.translate_mm[0], params.translate_mm[1], array_z + params.translate_mm[2]};
    MicrolensArray array = make_microlens_array(params.grid, params.pitch_mm, make_microlens(params), params.distance_mm,
                                                make_array_pose(params.rotate_deg, centre));
    array.abbe = params.abbe;
    if (params.has_errors)
        array.errors = LensErrors::drawn(params.errors);
    else if (!params.lens_table_file.empty()) {
        // A row's focal_length_mm becomes a factor of its type's focal length as the microlens gives
        // it (a refracting cap's paraxial one; none for pinholes).
        std::vector<double> type_focal_mm;
        if (array.microlens->forms_image())
            for (int type = 0; type < array.lens_type_count; ++type)
                type_focal_mm.push_back(array.microlens->focal_length_mm(type));
        array.errors = LensErrors::tabled(params.lens_table ? *params.lens_table : std::vector<LensTableRow>(),
                                          params.lens_table_file, type_focal_mm.data(), int(type_focal_mm.size()));
    }
    array.fill_factor = params.fill_factor;
    array.aperture_scale = params.fill_factor == 1 ? 1 : std::sqrt(params.fill_factor);
    array.mask = params.mask;
    array.baffles = params.baffles;
    return array;
}

} // namespace plenoptic
