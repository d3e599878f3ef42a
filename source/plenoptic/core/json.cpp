// SPDX-License-Identifier: AGPL-3.0-or-later

#include "plenoptic/core/json.h"

#include <cmath>
#include <cstdint>

namespace plenoptic {

MetadataJson json_number(double value)
{
    if (!std::isfinite(value))
        return nullptr;
    if (value == std::floor(value) && std::fabs(value) < 9007199254740992.0)
        return MetadataJson(static_cast<std::int64_t>(value));
    return MetadataJson(value);
}

MetadataJson json_number_or_null(bool present, double value)
{
    return present ? json_number(value) : MetadataJson(nullptr);
}

MetadataJson json_numbers(const double* values, int count)
{
    MetadataJson array = MetadataJson::array();
    for (int i = 0; i < count; ++i)
        array.push_back(json_number(values[i]));
    return array;
}

MetadataJson json_numbers(Vec3 v)
{
    const double values[3] = {v.x, v.y, v.z};
    return json_numbers(values, 3);
}

} // namespace plenoptic
