// SPDX-License-Identifier: AGPL-3.0-or-later
// The microlenses of an array: one interface for every kind of microlens, with one implementation
// per kind, each answering for itself (what it is called, whether it forms an image, its focal
// lengths, how it passes a ray). Nothing outside this folder asks which kind the lenses are; it asks
// the lens. The array (array/microlens_array.h) places the lenses and says which lens type each is.

#ifndef PLENOPTIC_MICROLENS_H
#define PLENOPTIC_MICROLENS_H

#include <memory>
#include <vector>

#include "plenoptic/core/lattice.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

struct MicrolensArray;
struct LensFrame;

// A ray leaving a microlens: where it leaves (optics frame, mm) and its direction (any length).
// passed false: there is no such ray (the other fields are then meaningless). `sampled`: the
// point of the array's plane that the sample picked (sample_ray), where the solid angle the sample
// stands for is measured from the sensor point; the origin itself for lenses without thickness.
struct ArrayRay {
    Vec3 origin;
    Vec3 direction;
    bool passed;
    Vec3 sampled;
};

// The lenses of one array, all of one kind. Lens types (multi-focus arrays have 3) differ only in
// their first-order data; the array says which type a lens is (MicrolensArray::type_of). Rays are
// passed in the array's own frame (its pose, MicrolensArray::to_local); every method takes the
// array for its lattice and pose.
class Microlens {
public:
    virtual ~Microlens() {}

    // What the metadata calls this kind of lens (microlens_array.lens: "pinhole", "thin_lens",
    // "refracting").
    virtual const char* kind_name() const = 0;
    // A pinhole forms no image: light passes it only at its centre, undeviated; it has no focal
    // length, nothing blurs through it, and it has no area to be lit through or to diffract.
    // A lens that forms one passes light anywhere in its lattice cell.
    virtual bool forms_image() const = 0;
    // Whether first-order optics is exact for these lenses (a thin lens of focal_length_mm in the
    // array's plane, or a pinhole), so that bounds built on it hold. False for refracting lenses,
    // whose thickness and spherical aberration first-order optics leaves out.
    virtual bool first_order_exact() const { return true; }
    // How far the lenses' glass extends from the array's plane towards the scene (mm): 0 for lenses
    // without thickness.
    virtual double thickness_mm() const { return 0; }
    // How many lens types the array's lenses come in (1, or 3 for a multi-focus array).
    virtual int type_count() const { return 1; }
    // The paraxial focal length of lens type `type` (0 <= type < type_count()); only for lenses that
    // form an image (a pinhole has none: NaN).
    virtual double focal_length_mm(int type) const = 0;
    // The focal length of each lens type, as the metadata lists them; empty for a pinhole.
    std::vector<double> focal_lengths_mm() const;

    // The same lenses with every power multiplied by `factor` (their glass at another wavelength:
    // MicrolensArray::at_wavelength); nullptr for lenses without power (a pinhole).
    virtual std::shared_ptr<const Microlens> with_power_scaled(double factor) const
    {
        (void)factor;
        return nullptr;
    }

    // The ray from sensor point p (optics frame) through lens `lens` for the aperture sample (u, v)
    // in [0, 1)^2, as it leaves the array towards the scene: through the pinhole's centre, or
    // through the point of the lens's cell the sample picks (uniform over the cell, (0.5, 0.5) the
    // centre), bent by the lens. Not passed when p is not behind the array. Per sample: no
    // allocation, no search, no trigonometry.
    virtual ArrayRay sample_ray(const MicrolensArray& array, const Vec3& p, LensIndex lens, double u, double v) const = 0;

    // Whether the camera may aim a pixel's samples at the part of a cell (and of the pixel) where
    // light can pass (camera/aim.h): only for lenses that act as ideal thin lenses of their focal
    // length (focal_length_mm of the lens's type), whose rays through cell points are affine in
    // the point; false for every other kind, which is then sampled uniformly over its cell.
    virtual bool aims() const { return false; }
    // For a lens that aims: the ray from sensor point p through the point `offset` (array-local,
    // from the lens's centre) of lens `lens`'s cell, as sample_ray makes it for the sample that
    // picks that point. Lenses that do not aim have none (not passed).
    virtual ArrayRay cell_ray(const MicrolensArray& array, const Vec3& p, LensIndex lens, Vec2 offset) const
    {
        (void)array;
        (void)p;
        (void)lens;
        (void)offset;
        return ArrayRay{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}};
    }

    // The same through a lens whose frame (MicrolensArray::frame) the caller holds: what cell_ray
    // does for an array with errors or a fill factor, without looking the lens up again (the aim
    // keeps the frames of the lenses it aims at).
    virtual ArrayRay cell_ray_in(const MicrolensArray& array, const Vec3& p, const LensFrame& frame, Vec2 offset) const
    {
        (void)array;
        (void)p;
        (void)frame;
        (void)offset;
        return ArrayRay{Vec3{0, 0, 0}, Vec3{0, 0, 0}, false, Vec3{0, 0, 0}};
    }

    // The ray from sensor point p through lens `lens` that leaves the lens heading for `target` (a
    // point in front of the array: a pinhole main lens), returned from `target` on. Not passed when
    // there is none (a pinhole's only ray from p misses any given point but by chance), when p or
    // the target is on the wrong side of the array, or, with check_cell, when the ray crosses the
    // lens plane outside the lens's cell.
    virtual ArrayRay ray_through(const MicrolensArray& array, const Vec3& p, LensIndex lens, Vec3 target,
                                 bool check_cell) const = 0;

    // Light arriving from the scene at point h of lens `lens`'s plane, travelling along `direction`
    // (optics frame, any length): the ray leaving the lens towards the sensor, from h. Not passed
    // when the light does not head towards the sensor side.
    virtual ArrayRay towards_sensor(const MicrolensArray& array, LensIndex lens, Vec3 h, Vec3 direction) const = 0;
};

// Pinholes.
std::shared_ptr<const Microlens> make_pinhole_microlens();
// Refracting lenses: array/refracting_microlens.h.
// Ideal thin lenses of focal lengths focal_mm[0 .. type_count - 1] (type_count 1 or 3): a ray
// meeting a lens at offset h from its centre, its direction normalised to unit component along the
// lens normal, leaves with w' = w - h / f, in either direction of travel.
std::shared_ptr<const Microlens> make_thin_microlens(const double* focal_mm, int type_count);

} // namespace plenoptic

#endif
