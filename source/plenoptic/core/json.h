// SPDX-License-Identifier: AGPL-3.0-or-later
// The metadata's JSON values (nlohmann-json, members kept in the order they are written) and how
// its numbers are stored, shared by every part that writes a section of it.

#ifndef PLENOPTIC_CORE_JSON_H
#define PLENOPTIC_CORE_JSON_H

#include <nlohmann/json.hpp>

#include "plenoptic/core/vec.h"

namespace plenoptic {

using MetadataJson = nlohmann::ordered_json;

// A finite number, or null (JSON has no NaN or infinity). Whole numbers below 2^53 are stored as
// integers so that they print without a fraction ("1000", not "1000.0"; -0 as 0); every other
// value prints in the library's shortest form that reads back to the same double (0.15, not
// 0.14999999999999999).
MetadataJson json_number(double value);
// json_number(value) when present, else null.
MetadataJson json_number_or_null(bool present, double value);
// An array of `count` json_numbers.
MetadataJson json_numbers(const double* values, int count);
// A vector as the array [x, y, z] of json_numbers.
MetadataJson json_numbers(Vec3 v);

} // namespace plenoptic

#endif
