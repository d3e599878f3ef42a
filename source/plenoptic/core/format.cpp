// SPDX-License-Identifier: AGPL-3.0-or-later
#include "plenoptic/core/format.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace plenoptic {

std::string format_number(double value)
{
    if (std::isnan(value))
        return "nan";
    if (std::isinf(value))
        return value > 0 ? "inf" : "-inf";
    char buffer[40];
    // The shortest of %.15g .. %.17g that reads back exactly: "0.1", not "0.10000000000000001".
    for (int precision = 15; precision <= 17; ++precision) {
        std::snprintf(buffer, sizeof buffer, "%.*g", precision, value);
        if (std::strtod(buffer, nullptr) == value)
            break;
    }
    return buffer;
}

} // namespace plenoptic
