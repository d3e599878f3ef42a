// SPDX-License-Identifier: AGPL-3.0-or-later
// Numbers in messages and metadata text.

#ifndef PLENOPTIC_FORMAT_H
#define PLENOPTIC_FORMAT_H

#include <string>

namespace plenoptic {

// Shortest text that reads back as the same double ("0.5", "1e-300", "nan").
std::string format_number(double value);

} // namespace plenoptic

#endif
