// SPDX-License-Identifier: AGPL-3.0-or-later
// traced_errors_on.pov: benchmarks/traced_errors.pov with its manufacturing errors on (for tools
// that take a scene file and no declarations, such as tools/compare-instructions; +Lbenchmarks).
#declare ERR = 1;
#include "traced_errors.pov"
