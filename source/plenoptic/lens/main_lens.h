// SPDX-License-Identifier: AGPL-3.0-or-later
// The main lens as ray generation sees it: one interface for every kind of lens (issue 13), with
// one implementation per kind. The optics frame has its origin at the main lens's reference point
// (the pinhole; the thin lens's plane), +z towards the scene, millimetres.

#ifndef PLENOPTIC_MAIN_LENS_H
#define PLENOPTIC_MAIN_LENS_H

#include <cmath>
#include <memory>

#include "plenoptic/camera/params.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

// A ray leaving the camera: origin and unit direction (towards the scene, +z component), mm.
struct SceneRay {
    Vec3 origin;
    Vec3 dir;
    bool passed;  // false: blocked by an aperture, or no such ray
};

// A ray leaving the main lens towards the image side (to_image): origin and unit direction (-z
// component), mm.
struct ImageRay {
    Vec3 origin;
    Vec3 dir;
    bool passed;  // false: blocked by an aperture, or no such ray
};

// A point in homogeneous coordinates (xyz / w; w = 0: at infinity in the direction xyz).
struct HomogeneousPoint {
    Vec3 xyz;
    double w;
};

class MainLens {
public:
    virtual ~MainLens() {}
    virtual MainLensType type() const = 0;

    // The centre of the exit pupil: image-side lines through it find a sensor point's own
    // microlens and the microimage centres.
    virtual Vec3 exit_pupil_centre() const = 0;
    // Radius of the exit pupil (0 for a pinhole).
    virtual double exit_pupil_radius() const = 0;
    // The point of the exit pupil for aperture sample (u, v) in [0, 1)^2 (uniform over its area).
    virtual Vec3 exit_pupil_point(double u, double v) const = 0;

    // The ray that leaves into the scene when light travels backwards from the image side along
    // (origin, direction) (direction towards +z, any length). Blocked (passed false) when it misses
    // an aperture (only if check_apertures) or cannot pass the lens at all.
    virtual SceneRay to_scene(Vec3 origin, Vec3 direction, bool check_apertures) const = 0;

    // The reverse: the ray that leaves towards the image side when light from the scene travels
    // along (origin, direction) (origin in front of the lens, direction towards -z, any length).
    // Blocked as to_scene blocks. Forward projection traces points' light with it.
    virtual ImageRay to_image(Vec3 origin, Vec3 direction, bool check_apertures) const = 0;

    // The paraxial image of a scene point (optics frame), homogeneous so that an image at
    // infinity is fine. A pinhole forms none: it returns the point itself with w = 1 (unused).
    virtual HomogeneousPoint paraxial_image(Vec3 point) const = 0;
};

struct Prescription;

// A prescription lens in the optics frame: its rear vertex at the origin, its front vertex at
// z = the lens's length (towards the scene), the stop at its written diameter unless stop_mm > 0.
// `exact`: rays are traced surface by surface (Snell, every clear aperture, the stop or iris);
// otherwise the lens is its paraxial equivalent, a thick lens: an ideal lens of the prescription's
// effective focal length between its principal planes, with its exit pupil as the aperture.
// The exit pupil (exit_pupil_centre, exit_pupil_radius) is the image of the aperture that limits
// the axial beam converging image_distance_mm behind the rear vertex (the array, or the sensor;
// paraxial_data); of the stop when image_distance_mm is not given (NaN).
// nullptr when the prescription has no paraxial data (afocal, or a pupil at infinity).
std::shared_ptr<const MainLens> make_prescription_lens(const Prescription& lens, double stop_mm, bool exact,
                                                       double image_distance_mm = NAN);

// The main lens of checked parameters (nullptr for none). A lens knows only itself, and D
// (distance_mm: main lens to array, or sensor) only for a thin lens's distortion, which acts on
// the plane z = -D, and for a real lens's pupils (the images of the aperture that limits the
// axial beam converging at z = -D).
std::shared_ptr<const MainLens> make_main_lens(const MainLensParams& params, double distance_mm);

// The unit-direction ray (origin, direction); passed false when it is not finite or does not head
// into the scene (a strong lens or a steep tilt can bend a ray back into the camera body).
SceneRay scene_ray(Vec3 origin, Vec3 direction);
// The same towards the image: passed false unless finite and heading towards -z.
ImageRay image_ray(Vec3 origin, Vec3 direction);

} // namespace plenoptic

#endif
