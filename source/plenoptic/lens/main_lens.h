// SPDX-License-Identifier: AGPL-3.0-or-later
// The main lens: one interface for every kind of lens, with one implementation per kind, each
// answering for itself (its pupils, its rays, its first-order data, what it is called). Nothing
// outside this folder asks which kind a lens is; it asks the lens. The optics frame has its origin at the main lens's reference point
// (the pinhole; the thin lens's plane), +z towards the scene, millimetres.

#ifndef PLENOPTIC_MAIN_LENS_H
#define PLENOPTIC_MAIN_LENS_H

#include <cmath>
#include <memory>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "plenoptic/core/vec.h"
#include "plenoptic/lens/distortion.h"
#include "plenoptic/lens/prescription.h"

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

// A disc in a plane z = const (optics frame) that light from the scene crosses before the lens,
// with the sag of the surface behind it (0 for a plane): every ray that passes the lens crosses the
// plane within the reach computed from it (forward projection's search window).
struct FrontWindow {
    double z, radius, sag;
};

class PupilBounds;
class LitAreaTable;

using MetadataJson = nlohmann::ordered_json;  // core/json.h

// What the metadata's main_lens section states about where the camera holds the lens: D (from
// the rear vertex, or the lens's plane, to the array or the sensor), the focus distance D came
// from (scene units; none when D was given directly), and the file a prescription came from
// ("" when it was written inline).
struct LensPlacement {
    double distance_mm;
    bool has_focus_distance;
    double focus_distance_units;
    std::string lens_file;
};

class MainLens {
public:
    virtual ~MainLens() {}

    // What the metadata calls this kind of lens ("pinhole", "thin_lens", "thick_lens",
    // "prescription") and how its chief rays are defined (metadata's main_lens.chief_ray).
    virtual const char* kind_name() const = 0;
    virtual const char* chief_ray_description() const = 0;

    // First-order data: effective focal length F, aperture diameter A (a real lens's stop) and
    // f-number (a real lens's: F / entrance-pupil diameter); all 0 for a pinhole.
    virtual double focal_length_mm() const { return 0; }
    virtual double aperture_mm() const { return 0; }
    virtual double f_number() const { return 0; }
    // A pinhole forms no image: every point is in focus, its pupil is a point, nothing blurs.
    virtual bool forms_image() const { return true; }
    // Traced surface by surface: points image where the trace takes them (distortion, aberration),
    // not where the paraxial image is, so projection and microimage centres are traced too.
    virtual bool traced() const { return false; }
    // A real lens's surfaces as used (stop sized, iris applied) and their paraxial data; nullptr
    // for the ideal lenses.
    virtual const Prescription* prescription() const { return nullptr; }
    virtual const ParaxialData* paraxial() const { return nullptr; }
    // A thin lens's parametric distortion (lens/distortion.h) as the scene gave it; nullptr when it
    // was given none, and for every other kind.
    virtual const DistortionParams* distortion() const { return nullptr; }
    // The window light from the scene crosses first (a prescription's first surface, the thin
    // lens's aperture, the thick lens's entrance pupil); false when the lens has none.
    virtual bool front_window(FrontWindow* window) const { (void)window; return false; }
    // The paraxial entrance pupil: optics-frame z and radius.
    virtual FrontWindow entrance_pupil() const { return FrontWindow{0, 0, 0}; }
    // Where light from points of the plane z = plane_z (the array, or the sensor) passes the lens:
    // made for a lens traced surface by surface (lens/pupil_bounds.h); nullptr for the others,
    // whose exit pupil says it.
    // With `tight`, the bounds also hold tight discs for aimed samples (PupilBounds, camera/aim.h).
    virtual std::shared_ptr<const PupilBounds> pupil_bounds(double plane_z, bool tight = false) const
    {
        (void)plane_z;
        (void)tight;
        return nullptr;
    }
    // Without an array: the lit area of the exit pupil's plane per sensor radius, from these
    // bounds, its samples weighted as the camera weighs them (irradiance_weight with K; K = 0:
    // flat); nullptr where the lens has no such table (an ideal lens, a blade iris).
    virtual std::shared_ptr<const LitAreaTable> lit_area(const PupilBounds& bounds, double irradiance_k_mm2,
                                                         double angular_exponent) const
    {
        (void)bounds;
        (void)irradiance_k_mm2;
        (void)angular_exponent;
        return nullptr;
    }
    // Advice when a render would be almost dark, or when microimages overlap by `free_mm` too
    // little on the array (magnification k = d / D): "" when the lens has none to give.
    virtual std::string dark_image_advice(double distance_mm) const { (void)distance_mm; return ""; }
    virtual std::string overlap_advice(double free_mm, double magnification) const
    {
        (void)free_mm;
        (void)magnification;
        return "";
    }

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

    // The same lens at a wavelength (nm): each dispersing medium at its index there (lens/glass.h),
    // its stop, iris and placement unchanged (so the pupils are those of the same apertures). nullptr
    // when the lens does not disperse: it is then the same lens at every wavelength.
    virtual std::shared_ptr<const MainLens> at_wavelength(double wavelength_nm) const
    {
        (void)wavelength_nm;
        return nullptr;
    }

    // The kind's own members of the metadata's main_lens section (docs/metadata.md), added after
    // the members every lens writes (main_lens_metadata): a thin lens's distortion, a real lens's
    // prescription and paraxial data.
    virtual void add_metadata(MetadataJson& section, const LensPlacement& placement) const
    {
        (void)section;
        (void)placement;
    }
};

// The metadata's main_lens section for `lens` held at `placement` (nullptr: no main lens, type
// "none"): type, focal length, aperture and f-number (null for a lens that forms no image), D,
// the focus distance, then the kind's own members. The camera adds the distortion profile it
// measures.
MetadataJson main_lens_metadata(const MainLens* lens, const LensPlacement& placement);

// A pinhole at the origin.
std::shared_ptr<const MainLens> make_pinhole_lens();
// An ideal thin lens in the plane z = 0: focal length F, aperture diameter A, f-number N (as the
// scene gave it, or F / A); with a parametric distortion acting on the plane z = plane_z (the
// array, or the sensor), or none (nullptr).
std::shared_ptr<const MainLens> make_thin_lens(double focal_length_mm, double aperture_mm, double f_number,
                                               const DistortionParams* distortion, double plane_z);

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

// The unit-direction ray (origin, direction); passed false when it is not finite or does not head
// into the scene (a strong lens or a steep tilt can bend a ray back into the camera body).
SceneRay scene_ray(Vec3 origin, Vec3 direction);
// The same towards the image: passed false unless finite and heading towards -z.
ImageRay image_ray(Vec3 origin, Vec3 direction);

} // namespace plenoptic

#endif
