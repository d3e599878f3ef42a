// SPDX-License-Identifier: AGPL-3.0-or-later
// What the per-thread caches of the camera's geometry (the aim's pixel plans and lenses, the overlap
// lenses' reach tests) depend on, to tell a cached camera from another: a camera copied or made at
// the same address differs in one of these when its geometry does. The key holds its parts (main
// lens, microlenses, pupil bounds, errors) alive, so that no other part can be made at the address
// of a part it names: a camera made after another was destroyed never passes for it.

#ifndef PLENOPTIC_CAMERA_CAMERA_KEY_H
#define PLENOPTIC_CAMERA_CAMERA_KEY_H

#include <memory>

#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

struct CameraKey {
    const PlenopticCamera* camera = nullptr;
    std::shared_ptr<const void> parts[4];
    double geometry[17] = {};
};

namespace detail {

inline void fill_geometry(const PlenopticCamera& m, double g[17])
{
    const Sensor& s = m.sensor;
    const ArrayPose& pose = m.array.pose;
    const double values[17] = {s.z_mm,
                               s.pixel_size_mm[0],
                               s.pixel_size_mm[1],
                               s.offset_mm[0],
                               s.offset_mm[1],
                               double(s.film.width),
                               double(s.film.height),
                               pose.centre_mm.x,
                               pose.centre_mm.y,
                               pose.centre_mm.z,
                               pose.rotation.m[0][0],
                               pose.rotation.m[0][1],
                               m.array.pitch_mm,
                               double(int(m.array.grid)),
                               m.array.fill_factor,
                               m.array.mask ? 1.0 : 0.0,
                               m.overlap.reach_mm};
    for (int k = 0; k < 17; ++k)
        g[k] = values[k];
}

} // namespace detail

inline CameraKey key_of(const PlenopticCamera& m)
{
    CameraKey key;
    key.camera = &m;
    key.parts[0] = m.lens;
    key.parts[1] = m.array.microlens;
    key.parts[2] = m.pupil_bounds;
    key.parts[3] = m.array.errors;
    detail::fill_geometry(m, key.geometry);
    return key;
}

// Whether k is m's key (key_of(m) == k), field by field without making the key (asked once or
// twice a sample); NaN never matches.
inline bool key_is(const CameraKey& k, const PlenopticCamera& m)
{
    const Sensor& s = m.sensor;
    const ArrayPose& pose = m.array.pose;
    const double* g = k.geometry;
    return k.camera == &m && k.parts[0].get() == m.lens.get() && k.parts[1].get() == m.array.microlens.get() &&
           k.parts[2].get() == m.pupil_bounds.get() && k.parts[3].get() == m.array.errors.get() && g[0] == s.z_mm &&
           g[1] == s.pixel_size_mm[0] && g[2] == s.pixel_size_mm[1] && g[3] == s.offset_mm[0] &&
           g[4] == s.offset_mm[1] && g[5] == double(s.film.width) && g[6] == double(s.film.height) &&
           g[7] == pose.centre_mm.x && g[8] == pose.centre_mm.y && g[9] == pose.centre_mm.z &&
           g[10] == pose.rotation.m[0][0] && g[11] == pose.rotation.m[0][1] && g[12] == m.array.pitch_mm &&
           g[13] == double(int(m.array.grid)) && g[14] == m.array.fill_factor && g[15] == (m.array.mask ? 1.0 : 0.0) &&
           g[16] == m.overlap.reach_mm;
}

} // namespace plenoptic

#endif
