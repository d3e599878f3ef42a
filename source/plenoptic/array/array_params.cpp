// SPDX-License-Identifier: AGPL-3.0-or-later
// From the array's specification to the array.

#include "plenoptic/array/array_params.h"

namespace plenoptic {

std::shared_ptr<const Microlens> make_microlens(const ArrayParams& params)
{
    switch (params.lens) {
    case MicrolensType::ThinLens:
        return make_thin_microlens(params.focal_lengths_mm, params.focal_length_count == 3 ? 3 : 1);
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
    return array;
}

} // namespace plenoptic
