// SPDX-License-Identifier: AGPL-3.0-or-later
// Camera builders and independent reference maths shared by the plenoptic unit tests.

#ifndef PLENOPTIC_TEST_UTIL_H
#define PLENOPTIC_TEST_UTIL_H

#include <cmath>
#include <sstream>
#include <string>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/optics.h"
#include "plenoptic/lens/prescription.h"

namespace plenoptic {
namespace test {

inline std::string str(Vec3 v)
{
    std::ostringstream out;
    out.precision(17);
    out << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return out.str();
}

// A made-up triplet of about 53 mm with large outer elements and a small stop (the Python tests'
// real_lens_scenes.LENS_ROWS): at full aperture the clear apertures cut the off-axis bundles into
// cat's eyes.
inline Prescription vignetting_triplet()
{
    Prescription lens;
    lens.surfaces.push_back(LensSurface{30, 6, 1.6, 24, false, 1});
    lens.surfaces.push_back(LensSurface{-200, 4, 1, 24, false, 2});
    lens.surfaces.push_back(LensSurface{0, 4, 1, 10, true, 3});
    lens.surfaces.push_back(LensSurface{-40, 2, 1.6, 14, false, 4});
    lens.surfaces.push_back(LensSurface{60, 4, 1, 14, false, 5});
    lens.surfaces.push_back(LensSurface{100, 5, 1.6, 18, false, 6});
    lens.surfaces.push_back(LensSurface{-40, 0, 1, 18, false, 7});
    return lens;
}

// The kind of a model's main lens, as the metadata names it ("none" without one).
inline std::string lens_kind(const PlenopticCamera& m) { return m.lens ? m.lens->kind_name() : "none"; }

inline Vec3 origin_of(const OpticsRay& r) { return Vec3{r.origin_mm.x, r.origin_mm.y, r.origin_mm.z}; }
inline Vec3 dir_of(const OpticsRay& r) { return Vec3{r.dir.x, r.dir.y, r.dir.z}; }

// A thin main lens with no array.
inline CameraParams thin_lens_camera(double focal_mm, double f_number, double distance_mm)
{
    CameraParams p;
    p.main.given = true;
    p.main.type = MainLensType::ThinLens;
    p.main.has_focal_length = true;
    p.main.focal_length_mm = focal_mm;
    p.main.has_f_number = true;
    p.main.f_number = f_number;
    p.main.has_distance = true;
    p.main.distance_mm = distance_mm;
    return p;
}

inline void add_array(CameraParams* p, GridType grid, double pitch_mm, double micro_focal_mm, double distance_mm)
{
    p->array.given = true;
    p->array.grid = grid;
    p->array.has_pitch = true;
    p->array.pitch_mm = pitch_mm;
    p->array.has_lens = true;
    if (micro_focal_mm > 0) {
        p->array.lens = MicrolensType::ThinLens;
        p->array.focal_length_count = 1;
        p->array.focal_lengths_mm[0] = micro_focal_mm;
    } else {
        p->array.lens = MicrolensType::Pinhole;
        p->array.focal_length_count = 0;
    }
    p->array.has_distance = true;
    p->array.distance_mm = distance_mm;
}

// Plenoptic camera: thin main lens (F, N, D) and a thin-lens array (pitch, f, d); f <= 0: pinholes.
inline CameraParams plenoptic_camera(GridType grid, double pitch_mm, double micro_focal_mm, double array_distance_mm,
                                     double focal_mm, double f_number, double main_distance_mm)
{
    CameraParams p = thin_lens_camera(focal_mm, f_number, main_distance_mm);
    add_array(&p, grid, pitch_mm, micro_focal_mm, array_distance_mm);
    return p;
}

// The main lens made a traced prescription (in place of plenoptic_camera's thin lens).
inline void use_prescription(CameraParams* p, const Prescription& lens)
{
    p->main.type = MainLensType::Prescription;
    p->main.has_focal_length = false;
    p->main.has_f_number = false;
    p->main.has_prescription = true;
    p->main.prescription = lens;
}

// Refracting microlenses in place of the array's thin ones: plano-convex caps of radius R and index n,
// cap_mm tall on substrate_mm of glass (the curved side to the scene unless the caller turns it).
inline void use_refracting_caps(CameraParams* p, double radius_mm, double ior, double cap_mm, double substrate_mm)
{
    p->array.lens = MicrolensType::Refracting;
    p->array.focal_length_count = 0;
    p->array.refracting.radius_mm = radius_mm;
    p->array.refracting.ior = ior;
    p->array.refracting.cap_mm = cap_mm;
    p->array.refracting.substrate_mm = substrate_mm;
}

inline void set_pose(CameraParams* p, double rx, double ry, double rz, double tx, double ty, double tz)
{
    p->array.rotate_deg[0] = rx;
    p->array.rotate_deg[1] = ry;
    p->array.rotate_deg[2] = rz;
    p->array.translate_mm[0] = tx;
    p->array.translate_mm[1] = ty;
    p->array.translate_mm[2] = tz;
}

// Independent rotation: the three textbook right-hand-rule matrices, applied x first.
inline Vec3 reference_rotate(const double deg[3], Vec3 v)
{
    const double ax = deg[0] * kPi / 180, ay = deg[1] * kPi / 180, az = deg[2] * kPi / 180;
    // about x
    Vec3 a{v.x, std::cos(ax) * v.y - std::sin(ax) * v.z, std::sin(ax) * v.y + std::cos(ax) * v.z};
    // about y
    Vec3 b{std::cos(ay) * a.x + std::sin(ay) * a.z, a.y, -std::sin(ay) * a.x + std::cos(ay) * a.z};
    // about z
    return Vec3{std::cos(az) * b.x - std::sin(az) * b.y, std::sin(az) * b.x + std::cos(az) * b.y, b.z};
}

inline Vec3 reference_unrotate(const double deg[3], Vec3 v)
{
    const double ax = deg[0] * kPi / 180, ay = deg[1] * kPi / 180, az = deg[2] * kPi / 180;
    Vec3 b{std::cos(az) * v.x + std::sin(az) * v.y, -std::sin(az) * v.x + std::cos(az) * v.y, v.z};
    Vec3 a{std::cos(ay) * b.x - std::sin(ay) * b.z, b.y, std::sin(ay) * b.x + std::cos(ay) * b.z};
    return Vec3{a.x, std::cos(ax) * a.y + std::sin(ax) * a.z, -std::sin(ax) * a.y + std::cos(ax) * a.z};
}

// Brute-force nearest lattice centre around (x, y) (searches +-3 cells of the estimate).
inline LensIndex brute_force_nearest(GridType grid, double pitch, double x, double y)
{
    const double row = grid == GridType::Hexagonal ? pitch * std::sqrt(3.0) / 2 : pitch;
    const long long l0 = (long long)std::floor(y / row);
    const long long k0 = (long long)std::floor(x / pitch);
    LensIndex best{0, 0};
    double best_d2 = INFINITY;
    for (long long l = l0 - 3; l <= l0 + 3; ++l) {
        for (long long k = k0 - 3; k <= k0 + 3; ++k) {
            double cx = double(k) * pitch, cy = double(l) * row;
            if (grid == GridType::Hexagonal && ((l % 2) + 2) % 2 == 1)
                cx += pitch / 2;
            const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
            if (d2 < best_d2) {
                best_d2 = d2;
                best = LensIndex{k, l};
            }
        }
    }
    return best;
}

// Distance from point x to the line through origin o with direction d.
inline double distance_to_line(Vec3 x, Vec3 o, Vec3 d)
{
    const Vec3 rel = x - o;
    const Vec3 c = cross(rel, d);
    return length(c) / length(d);
}

} // namespace test
} // namespace plenoptic

#endif
