// SPDX-License-Identifier: AGPL-3.0-or-later
// Small 2-D and 3-D vector and 3x3 matrix helpers for the plenoptic optics.

#ifndef PLENOPTIC_VEC_H
#define PLENOPTIC_VEC_H

#include <cmath>

namespace plenoptic {

// The one definition of pi in the optics core.
const double kPi = 3.14159265358979323846;

struct Vec2 { double x, y; };
struct Vec3 { double x, y, z; };

inline Vec2 operator+(Vec2 a, Vec2 b) { return Vec2{a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return Vec2{a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return Vec2{s * a.x, s * a.y}; }

inline Vec3 operator+(Vec3 a, Vec3 b) { return Vec3{a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return Vec3{a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator-(Vec3 a) { return Vec3{-a.x, -a.y, -a.z}; }
inline Vec3 operator*(double s, Vec3 a) { return Vec3{s * a.x, s * a.y, s * a.z}; }

inline double dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }
inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
inline Vec3 cross(Vec3 a, Vec3 b)
{
    return Vec3{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(Vec2 a) { return std::hypot(a.x, a.y); }
inline double length(Vec3 a) { return std::sqrt(dot(a, a)); }

inline bool is_finite(Vec2 a) { return std::isfinite(a.x) && std::isfinite(a.y); }
inline bool is_finite(Vec3 a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }

// Unit vector; a zero or non-finite input gives a non-finite result, which callers reject.
inline Vec3 normalized(Vec3 a)
{
    // The usual case directly (one square root, one division: this runs for every ray).
    const double length_sq = dot(a, a);
    if (length_sq > 1e-280 && length_sq < 1e280)
        return (1.0 / std::sqrt(length_sq)) * a;
    // Otherwise scale first, so that huge components cannot overflow the squared length.
    const double big = std::fmax(std::fabs(a.x), std::fmax(std::fabs(a.y), std::fabs(a.z)));
    const Vec3 s = (1.0 / big) * a;
    return (1.0 / length(s)) * s;
}

// Row-major 3x3 matrix: m[row][column].
struct Mat3 { double m[3][3]; };

inline Mat3 identity_mat3() { return Mat3{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}; }

inline Vec3 mul(const Mat3& r, Vec3 v)
{
    return Vec3{r.m[0][0] * v.x + r.m[0][1] * v.y + r.m[0][2] * v.z,
                r.m[1][0] * v.x + r.m[1][1] * v.y + r.m[1][2] * v.z,
                r.m[2][0] * v.x + r.m[2][1] * v.y + r.m[2][2] * v.z};
}

// Multiply by the transpose, which is the inverse of a rotation.
inline Vec3 mul_transposed(const Mat3& r, Vec3 v)
{
    return Vec3{r.m[0][0] * v.x + r.m[1][0] * v.y + r.m[2][0] * v.z,
                r.m[0][1] * v.x + r.m[1][1] * v.y + r.m[2][1] * v.z,
                r.m[0][2] * v.x + r.m[1][2] * v.y + r.m[2][2] * v.z};
}

inline Mat3 mul(const Mat3& a, const Mat3& b)
{
    Mat3 out;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            out.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
    return out;
}

} // namespace plenoptic

#endif
