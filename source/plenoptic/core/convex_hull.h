// SPDX-License-Identifier: AGPL-3.0-or-later
// The convex hull of points of a plane (Andrew's monotone chain), for the aim's pixel regions and
// the pupil bounds' polygons. Header only.

#ifndef PLENOPTIC_CONVEX_HULL_H
#define PLENOPTIC_CONVEX_HULL_H

#include <algorithm>

#include "plenoptic/core/vec.h"

namespace plenoptic {

// Sorts points[0..n) and writes the corners of their convex hull to out (room for 2 n),
// counter-clockwise from the lowest of the leftmost points, points on its edges dropped; returns
// how many (fewer than three when the points lie on a line).
inline int convex_hull(Vec2* points, int n, Vec2* out)
{
    std::sort(points, points + n, [](Vec2 a, Vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    int h = 0;
    for (int pass = 0; pass < 2; ++pass) {  // the lower chain, then the upper
        const int start = h;
        for (int k = 0; k < n; ++k) {
            const Vec2 p = pass == 0 ? points[k] : points[n - 1 - k];
            while (h >= start + 2 && cross(out[h - 1] - out[h - 2], p - out[h - 2]) <= 0)
                --h;
            out[h++] = p;
        }
        --h;  // the chain's last point starts the other chain
    }
    return h;
}

} // namespace plenoptic

#endif
