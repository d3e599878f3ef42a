// SPDX-License-Identifier: AGPL-3.0-or-later
// A real main lens given by its prescription: the surfaces, read from pbrt's
// RealisticCamera lens files; its paraxial (first-order) data; and the exact trace of a ray
// through it, surface by surface, with Snell's law, total internal reflection and every clear
// aperture. Pure optics, no POV-Ray dependency.
//
// The lens frame: the optical axis is z, z = 0 at the front vertex (the first surface, object
// side), z increasing towards the image; lengths in mm. Signs follow the usual optics convention
// for light travelling towards +z: a radius is positive when the surface's centre of curvature
// lies on the image side of its vertex (+z).

#ifndef PLENOPTIC_PRESCRIPTION_H
#define PLENOPTIC_PRESCRIPTION_H

#include <cmath>
#include <string>
#include <vector>

#include "plenoptic/core/vec.h"
#include "plenoptic/lens/glass.h"

namespace plenoptic {

// One row of a prescription.
struct LensSurface {
    double radius_mm = 0;     // curvature radius; 0 for a flat surface (and for the stop)
    double thickness_mm = 0;  // axial distance to the next surface (after the last: to nothing, unused)
    double ior = 1;           // refractive index of the medium after the surface at the d line (1 for air)
    double aperture_mm = 0;   // clear aperture diameter
    bool stop = false;        // the aperture stop (a flat, non-refracting opening)
    int line = 0;             // where it was written (file or scene line, 0 when unknown)
    Glass glass;              // how the medium after the surface disperses (default: it does not)
    // Conic and even-asphere terms (surface_sag_mm): the conic constant k (0: a sphere, -1: a
    // paraboloid) and a4, a6, ..., a18 (mm^-3, mm^-5, ...), the first aspheric_count of them as
    // written (the rest 0). A surface with k = 0 and every term 0 is spherical (or flat) and is
    // traced as before.
    static const int kMaxAspheric = 8;
    double conic = 0;
    int aspheric_count = 0;
    double aspheric[kMaxAspheric] = {0, 0, 0, 0, 0, 0, 0, 0};

    LensSurface() = default;
    LensSurface(double radius, double thickness, double index, double aperture, bool is_stop, int at,
                const Glass& medium = Glass())
        : radius_mm(radius), thickness_mm(thickness), ior(index), aperture_mm(aperture), stop(is_stop), line(at),
          glass(medium) {}

    // The index of the medium after the surface at a wavelength (nm): ior at every wavelength when
    // it does not disperse.
    double index_at(double wavelength_nm) const { return plenoptic::index_at(ior, glass, wavelength_nm); }

    // Whether the surface departs from its sphere (or plane): a conic constant or an aspheric term
    // other than 0.
    bool is_aspheric() const
    {
        if (conic != 0)
            return true;
        for (int j = 0; j < kMaxAspheric; ++j)
            if (aspheric[j] != 0)
                return true;
        return false;
    }
};

// The sag of a surface (mm, +z towards the image) at distance r_mm from the axis:
//   z(r) = c r^2 / (1 + sqrt(1 - (1 + k) c^2 r^2)) + a4 r^4 + a6 r^6 + ... + a18 r^18
// with c = 1 / radius (0 for a flat surface) and k the conic constant (the even-asphere form
// without an r^2 term). NaN where the conic's root is not real; 0 for the stop. For a sphere it is
// R - sign(R) sqrt(R^2 - r^2).
double surface_sag_mm(const LensSurface& s, double r_mm);

// The surfaces, object side first.
struct Prescription {
    std::vector<LensSurface> surfaces;
    // Polygonal iris at the stop: `blades` straight blades (0: a circular stop), rotated by
    // blade_rotation_deg from +x (one blade's flat side at the rotation angle).
    int blades = 0;
    double blade_rotation_deg = 0;
};

// A refusal: what is wrong, at which 1-based line of the input (0: not tied to a line).
struct PrescriptionError {
    std::string message;  // empty: no error
    int line;
    bool any() const { return !message.empty(); }
};

struct ParsedPrescription {
    Prescription prescription;
    PrescriptionError error;
};

// Every length of a prescription is bounded as the camera's other lengths are (1e12 mm); a
// surface radius beyond it in magnitude is read as a flat surface (flat_radius).
const double kPrescriptionMaxLengthMm = 1e12;

// The radius a parser stores for a written surface radius: 0 (flat) beyond
// +-kPrescriptionMaxLengthMm, whose curvature no lens can show (a power below 1e-12 per mm) and
// whose sphere the trace cannot hold in double precision; the radius itself otherwise.
double flat_radius(double radius_mm);

// Reads pbrt's RealisticCamera lens file format: one surface per row, object side first, four
// numbers: curvature radius, thickness, index of refraction (of the medium after the surface, at
// the d line), aperture diameter, in mm; and optionally a fifth, the medium's Abbe number V_d
// (0: no dispersion; glass.h). A row with radius 0 is the aperture stop (pbrt writes its index as 0
// or 1: the stop does not refract either way); a refracting row with a radius beyond
// +-kPrescriptionMaxLengthMm is flat (flat_radius). `#` starts a comment; blank lines are skipped,
// and so is a leading UTF-8 byte-order mark. The prescription is checked (check_prescription)
// before it is returned.
ParsedPrescription parse_lens_file(const std::string& text);

// The refusals: no surface, no stop or more than one, a non-positive or non-finite
// number where one is needed, an index below 1, a surface whose clear aperture exceeds its
// sphere (aperture > 2 |radius|; a surface of radius 0, possible only inline, is flat), a negative thickness;
// a length beyond kPrescriptionMaxLengthMm (a radius there must have been made flat by the parser);
// two consecutive rows that cross inside the smaller of their clear apertures; a lens that
// has a negative effective focal length (a diverging lens, or a relay with an intermediate image:
// not supported as a main lens); a glass check_glass refuses, or a dispersing medium on the stop or
// on a row of index 1 (air, which the models leave at index 1 and Sellmeier terms would not).
PrescriptionError check_prescription(const Prescription& lens);

// Whether any medium of the lens disperses.
bool dispersive(const Prescription& lens);

// The lens at a wavelength (nm): each medium at its index there (LensSurface::index_at) and no
// glass model left; the lens itself when it does not disperse. Tracing or a paraxial trace at a
// wavelength is that of this prescription.
Prescription prescription_at_wavelength(const Prescription& lens, double wavelength_nm);

// The paraxial focal data at the F, d and C lines (glass.h) of a dispersing lens, infinity focus.
struct LineFocus {
    const char* line;      // "F", "d", "C"
    double wavelength_nm;
    double efl_mm;         // effective focal length
    double bfd_mm;         // back focal distance: rear vertex -> rear focal point
};
struct ChromaticFocus {
    bool valid = false;            // false for a lens that does not disperse or is afocal at a line
    LineFocus lines[3] = {};       // F, d, C
    double longitudinal_colour_mm = 0;  // back focus at F minus back focus at C (negative: F focuses nearer)
};
ChromaticFocus chromatic_focus(const Prescription& lens);

// The iris's turn reduced by its symmetry: degrees modulo 360 / blades (360 without an iris),
// in [0, 360 / blades). A rotation of 1e300 degrees is as valid as any and must not swamp the
// 360 / blades between the blades' angles.
double reduced_blade_rotation(double degrees, int blades);

// The z of each surface's vertex (the first at 0).
std::vector<double> vertex_positions(const Prescription& lens);

// First-order data, for light from the object side (index 1 before the lens and after it).
// Positions are z in the lens frame (from the front vertex, +z towards the image).
struct ParaxialData {
    bool valid = false;           // false for an afocal lens (no power) or a stop that images nowhere
    double efl_mm = 0;            // effective focal length
    double bfd_mm = 0;            // back focal distance: rear vertex -> rear focal point
    double ffd_mm = 0;            // front focal distance: front focal point -> front vertex
    double rear_vertex_z = 0;     // z of the last surface
    double front_focal_z = 0, rear_focal_z = 0;
    double front_principal_z = 0, rear_principal_z = 0;
    double entrance_pupil_z = 0, entrance_pupil_mm = 0;  // position and diameter
    double exit_pupil_z = 0, exit_pupil_mm = 0;
    double stop_z = 0, stop_mm = 0;
    double f_number = 0;          // efl / entrance pupil diameter (infinity focus)
    // The aperture whose images the pupils are: the stop, or (paraxial_data with an image
    // distance) the aperture that limits the axial beam (axial_limit); its index, z and diameter.
    int aperture_surface = -1;
    double aperture_z = 0, aperture_mm = 0;
    // The largest stop diameter at which the stop still limits that axial beam (infinity
    // without an image distance, or when no rim ever limits it).
    double largest_stop_mm = INFINITY;
};

// The paraxial data with the stop's diameter replaced by stop_mm (> 0), or as written (0). The
// pupils are the stop's images; with image_distance_mm (finite, the distance from the rear vertex
// to the axial image point: the array, or the sensor), they are the images of the aperture that
// limits the axial beam converging there (axial_limit), and f_number is the effective focal length
// over that entrance pupil.
ParaxialData paraxial_data(const Prescription& lens, double stop_mm = 0, double image_distance_mm = NAN);

// The aperture that limits the axial beam (first order): the one whose opening the paraxial
// marginal ray from the axial point image_distance_mm behind the rear vertex fills first, i.e.
// the smallest ratio of opening radius to marginal-ray height (of all apertures, the one whose
// paraxial image subtends the smallest angle from that point). The stop is preferred: a rim limits
// only when its ratio is smaller than the stop's by more than kApertureTolerance (relative).
const double kApertureTolerance = 0.005;
struct AxialLimit {
    bool valid = false;
    int surface = -1;              // the limiting aperture (the stop's index when the stop limits)
    int rim = -1;                  // the surface (not the stop) whose ratio is smallest; -1: none
    double largest_stop_mm = INFINITY;  // stop diameter at which `rim` takes over (first order)
};
AxialLimit axial_limit(const Prescription& lens, double image_distance_mm);

// Paraxial image of the plane at distance object_mm in front of the front vertex (> 0; infinity
// for an object at infinity): the distance from the rear vertex to its image (positive: behind
// the lens, where a sensor can be). `real` is false when the image is at infinity or in front of
// the rear vertex (the lens cannot focus there).
struct ImageDistance {
    bool real;
    double mm;
};
ImageDistance paraxial_image_distance(const Prescription& lens, double object_mm);

// A ray in the lens frame (mm): origin and unit direction.
struct LensRay {
    Vec3 origin;
    Vec3 dir;
};

// Meets a conic or aspheric surface (vertex at z) with a ray of unit direction: Newton's method on
// the sag from the base conic's hit (the vertex plane's when the ray misses the conic), converged
// when a step moves less than kAsphereToleranceMm along the ray, at most kAsphereIterations steps.
// False (the ray is blocked as missing the surface) when it does not converge, when the sag is
// undefined on its way, or when the hit lies behind the ray's origin. The normal is the sag's
// gradient's (unit, facing +z).
extern const double kAsphereToleranceMm;
extern const int kAsphereIterations;
bool meet_aspheric_surface(const LensSurface& s, double z, const LensRay& ray, Vec3* hit, Vec3* normal);

// Why a trace ended.
enum class TraceResult { Passed, Missed, ClearAperture, Stop, TotalInternalReflection };

struct Traced {
    TraceResult result;
    LensRay ray;  // Passed: the ray leaving the lens; otherwise the ray as it was when blocked
    int surface;  // the surface that blocked it (-1 when it passed)
};

// Traces a ray that starts on the image side of the lens and travels towards the object
// (dir.z < 0) through every surface, last to first; on success the ray leaving the front surface
// into object space. Blocked by a surface it misses or meets outside its clear aperture, by the
// stop (circle or iris polygon), by total internal reflection.
Traced trace_from_image(const Prescription& lens, const LensRay& in);

// The same from the object side towards the image (dir.z > 0), first surface to last.
Traced trace_from_object(const Prescription& lens, const LensRay& in);

// A prescription with what tracing needs worked out once (each vertex's z, the index on either
// side of each surface), so that a trace allocates nothing and costs linear time in the surfaces:
// the per-ray form of the two functions above, which build one each call.
class TracingLens {
public:
    explicit TracingLens(const Prescription& lens);
    const Prescription& prescription() const { return lens_; }
    Traced trace_from_image(const LensRay& in) const;
    Traced trace_from_object(const LensRay& in) const;

private:
    Prescription lens_;
    std::vector<double> z_, before_, after_;
    std::vector<unsigned char> aspheric_;  // per surface: met by meet_aspheric_surface
    bool any_aspheric_ = false;            // chooses the trace once: spheres only, or with aspheres
};

// Stop diameter (mm) giving the paraxial f-number N (efl / the stop's entrance pupil diameter).
double stop_diameter_for_f_number(const Prescription& lens, double f_number);

// The f-number (efl / entrance pupil) of the stop at diameter stop_mm.
double f_number_for_stop_diameter(const Prescription& lens, double stop_mm);

} // namespace plenoptic

#endif
