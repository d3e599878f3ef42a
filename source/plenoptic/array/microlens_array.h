// SPDX-License-Identifier: AGPL-3.0-or-later
// The microlens array as the camera holds it: its lattice (rectangular or hexagonal, core/lattice.h),
// its pose in the optics frame, its lenses (one kind, array/microlens.h) and which lens type each
// lens is. It answers the questions its users used to work out from its fields: where a lens is,
// which lens a point belongs to, a lens's type and focal length, the array's own frame.

#ifndef PLENOPTIC_MICROLENS_ARRAY_H
#define PLENOPTIC_MICROLENS_ARRAY_H

#include <memory>

#include <nlohmann/json_fwd.hpp>

#include "plenoptic/array/lens_errors.h"
#include "plenoptic/array/microlens.h"
#include "plenoptic/core/lattice.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

// Pose of the microlens array in the optics frame: q_optics = centre_mm + rotation * q_local.
struct ArrayPose {
    Mat3 rotation = Mat3();  // array-local -> optics frame, Rz * Ry * Rx
    Vec3 centre_mm = Vec3();  // where the array's lens (0, 0) sits
    Vec3 normal = Vec3();  // rotation * (0, 0, 1): towards the scene
    bool tilted = false;  // rotated about x or y: the array plane is not parallel to the sensor
    double tilt_sine = 0;  // sine of the angle between the array's normal and the optical axis
};

// Rotation about x, then y, then z, in degrees: v -> Rz * Ry * Rx * v, with the same
// matrices as POV-Ray's Compute_Rotation_Transform (which applies them to row vectors).
// Multiples of 90 degrees are exact.
Mat3 rotation_from_degrees(const double degrees[3]);

// The pose rotated by `rotate_deg` (about x, then y, then z) with lens (0, 0) at centre_mm.
ArrayPose make_array_pose(const double rotate_deg[3], Vec3 centre_mm);

// One lens as it is (its manufacturing errors applied): its centre in the array's own frame, its
// optical axis and its focal length. axes maps the lens's own frame (its cell in the plane z = 0
// about its centre, its axis +z) to the array's; the identity when it is not tilted.
struct LensFrame {
    Vec3 centre;
    bool tilted;
    Mat3 axes;
    double focal_mm;  // NaN for a pinhole
};

// The array. present() false: the camera has none; grid is then None, every number 0, microlens
// nullptr, and the pose unrotated at the plane where an array would be (z = -D; 0 without a main
// lens), so that distances measured to it stay defined. The methods below that concern lenses are
// for a present array only.
struct MicrolensArray {
    GridType grid = GridType::None;
    double pitch_mm = 0;
    std::shared_ptr<const Microlens> microlens;  // the lenses' kind and first-order data
    int lens_type_count = 0;  // microlens->type_count(): 1, or 3 for multi-focus arrays
    double distance_mm = 0;  // d, to the sensor; 0 without array
    ArrayPose pose;
    double cell_inradius_mm = 0;  // of a lens's lattice cell
    double cell_circumradius_mm = 0;
    // The microlenses' glass: their Abbe number V_d (0: they do not disperse). At a wavelength a
    // microlens's power scales with (n(lambda) - 1) / (n_d - 1) of the two-term model (lens/glass.h),
    // which V_d alone fixes (at_wavelength).
    double abbe = 0;
    // Manufacturing errors, lens by lens (array/lens_errors.h); nullptr: every lens is ideal.
    std::shared_ptr<const LensErrors> errors;
    // The part of each cell that is lens: a copy of the cell scaled by sqrt(fill_factor) about the
    // lens centre (aperture_scale); the rest of the cell is a gap of flat substrate, through which
    // light passes unbent, or which a mask (mask true) blocks.
    double fill_factor = 1;
    double aperture_scale = 1;
    bool mask = false;
    // Walls between the microimages: a pixel receives light through its own lens only. Off (real
    // arrays have none): light leaving a lens lands wherever it lands, under a neighbour's
    // microimage too (PlenopticCamera::overlap).
    bool baffles = false;

    bool present() const { return grid != GridType::None; }
    // Every lens lies in the array's plane (no error moves or tilts one out of it): what the main
    // lens's pupil bounds, made for points of that plane, need.
    bool lenses_in_plane() const { return !errors || (errors->max_dz_mm() == 0 && !errors->tilts()); }

    // The array's own frame (lens (0, 0) at the origin, the lenses in its plane z = 0) and back.
    Vec3 to_local(Vec3 optics) const { return mul_transposed(pose.rotation, optics - pose.centre_mm); }
    Vec3 to_optics(Vec3 local) const { return pose.centre_mm + mul(pose.rotation, local); }

    // A lens's lattice point (array-local, in its plane): where an ideal array has its centre.
    Vec2 lattice_centre_local(LensIndex lens) const { return lens_centre(grid, pitch_mm, lens); }
    // The lens's error (the ideal lens's when the array has none).
    LensError error_of(LensIndex lens) const { return errors ? errors->at(lens) : LensError(); }
    // Lens centres as they are: array-local in its plane (x, y), array-local in 3-D (with the
    // displacement along the normal), and in the optics frame.
    Vec2 centre_local(LensIndex lens) const
    {
        const Vec2 c = lattice_centre_local(lens);
        if (!errors)
            return c;
        const LensError& e = errors->at(lens);
        return Vec2{c.x + e.dx_mm, c.y + e.dy_mm};
    }
    Vec3 centre_local3(LensIndex lens) const
    {
        const Vec2 c = lattice_centre_local(lens);
        if (!errors)
            return Vec3{c.x, c.y, 0};
        const LensError& e = errors->at(lens);
        return Vec3{c.x + e.dx_mm, c.y + e.dy_mm, e.dz_mm};
    }
    Vec3 centre_mm(LensIndex lens) const { return to_optics(centre_local3(lens)); }
    // The lens whose cell contains the array-local point (x, y): its lattice cell
    // (core/lattice.h: nearest_lens) for an ideal array; with errors, the lens whose actual centre
    // is nearest, among that cell's lens and its neighbours (the cells of displaced lenses move
    // with them).
    LensIndex nearest(double x, double y) const
    {
        const LensIndex lattice = nearest_lens(grid, pitch_mm, x, y);
        return errors ? nearest_displaced(lattice, x, y) : lattice;
    }
    // Which lens type a lens is (0 .. lens_type_count - 1), and its focal length (lenses that form
    // an image only), its error included.
    int type_of(LensIndex lens) const { return lens_type_count == 1 ? 0 : lens_type(lens, lens_type_count); }
    double focal_length_mm(LensIndex lens) const
    {
        const double f = microlens->focal_length_mm(type_of(lens));
        return errors ? f * errors->at(lens).focal_factor : f;
    }
    // The lens as it is: centre, axis and focal length in one lookup.
    LensFrame frame(LensIndex lens) const
    {
        const double f = microlens->focal_length_mm(type_of(lens));
        const Vec2 c = lattice_centre_local(lens);
        if (!errors)
            return LensFrame{Vec3{c.x, c.y, 0}, false, identity_mat3(), f};
        const LensError& e = errors->at(lens);
        return LensFrame{Vec3{c.x + e.dx_mm, c.y + e.dy_mm, e.dz_mm}, e.tilted(),
                         e.tilted() ? frame_to_axis(e.axis) : identity_mat3(), f * e.focal_factor};
    }
    // Whether a point of a lens's cell (relative to its centre, in its plane) is lens rather than
    // gap (fill_factor).
    bool in_aperture(Vec2 offset) const
    {
        if (aperture_scale == 1)
            return true;
        const LensIndex own = nearest_lens(grid, pitch_mm * aperture_scale, offset.x, offset.y);
        return own.k == 0 && own.l == 0;
    }

    // A lens's cell, relative to its centre: the point for the sample (u, v) in [0, 1)^2 (uniform,
    // (0.5, 0.5) the centre), and its corners counter-clockwise (returns 4 or 6).
    Vec2 cell_point(double u, double v) const { return sample_cell_uniform(grid, pitch_mm, u, v); }
    int cell_corners(Vec2 corners[6]) const { return cell_polygon(grid, pitch_mm, corners); }
    // Distance between rows of lenses: p, or p sqrt(3)/2.
    double row_spacing_mm() const { return row_spacing(grid, pitch_mm); }

    // The same array at a wavelength (nm): each lens's power scaled by two_term_power_ratio(abbe)
    // (lens/glass.h); the array itself when its lenses do not disperse or have no power.
    MicrolensArray at_wavelength(double wavelength_nm) const;

    // The metadata's microlens_array section (present arrays only): grid, lens kind, pitch, the
    // focal lengths, d, and the pose as the scene gave it (degrees and mm, from the spec).
    nlohmann::ordered_json metadata(const double rotate_deg[3], const double translate_mm[3]) const;

private:
    LensIndex nearest_displaced(LensIndex lattice, double x, double y) const;
};

// No array: see MicrolensArray; plane_z is where an array would be.
MicrolensArray no_microlens_array(double plane_z);
// An array of `microlens` lenses on a `grid` lattice of pitch pitch_mm, d = distance_mm in front of
// the sensor, posed by `pose`.
MicrolensArray make_microlens_array(GridType grid, double pitch_mm, std::shared_ptr<const Microlens> microlens,
                                    double distance_mm, const ArrayPose& pose);

} // namespace plenoptic

#endif
