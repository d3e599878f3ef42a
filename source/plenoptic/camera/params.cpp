// SPDX-License-Identifier: AGPL-3.0-or-later
// Parse-time checks of the plenoptic camera's parameters: per value and per block.

#include "plenoptic/camera/params.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/lens/glass.h"

namespace plenoptic {


namespace {

std::string str(const char* text) { return std::string(text); }

bool is_whole(double value) { return std::floor(value) == value; }

} // namespace

std::string check_finite(const char* keyword, double value)
{
    if (std::isfinite(value))
        return "";
    return str(keyword) + " must be a finite number, got " + format_number(value);
}

std::string check_positive_length(const char* keyword, double value_mm)
{
    std::string finite = check_finite(keyword, value_mm);
    if (!finite.empty())
        return finite;
    if (value_mm >= kMinLengthMm && value_mm <= kMaxLengthMm)
        return "";
    if (value_mm > 0)
        return str(keyword) + " must be a length from " + format_number(kMinLengthMm) + " to " +
               format_number(kMaxLengthMm) + " mm, got " + format_number(value_mm);
    return str(keyword) + " must be a positive length in mm (> 0), got " + format_number(value_mm);
}

std::string check_f_number(double value)
{
    std::string finite = check_finite("f_number", value);
    if (!finite.empty())
        return finite;
    if (value > 0)
        return "";
    return "f_number must be positive (> 0), got " + format_number(value);
}

std::string check_mm_per_unit(double value)
{
    std::string finite = check_finite("mm_per_unit", value);
    if (!finite.empty())
        return finite;
    if (value > 0)
        return "";
    return "mm_per_unit must be a positive number of millimetres per scene unit (> 0), got " +
           format_number(value);
}

std::string check_focus_distance(double value_units)
{
    std::string finite = check_finite("focus_distance", value_units);
    if (!finite.empty())
        return finite;
    if (value_units > 0)
        return "";
    return "focus_distance must be a positive distance in scene units (> 0), got " +
           format_number(value_units);
}

std::string check_angle(const char* keyword, double degrees)
{
    if (std::isfinite(degrees))
        return "";
    return str(keyword) + " must be a finite angle in degrees, got " + format_number(degrees);
}

std::string check_translation(const char* keyword, double value_mm)
{
    // Bounded as lengths are: beyond 1e12 mm squared distances overflow (a fuzzed array
    // translated by 8e283 mm gave NaN pixels under irradiance).
    if (std::isfinite(value_mm) && std::fabs(value_mm) <= kMaxLengthMm)
        return "";
    return str(keyword) + " must be a finite length from -" + format_number(kMaxLengthMm) + " to " +
           format_number(kMaxLengthMm) + " mm, got " + format_number(value_mm);
}

std::string check_samples(const char* keyword, double value)
{
    if (std::isfinite(value) && is_whole(value) && value >= 1 && value <= kMaxSamples)
        return "";
    return str(keyword) + " must be a whole number from 1 to " + std::to_string(kMaxSamples) +
           ", got " + format_number(value);
}

std::string check_confidence(double value)
{
    std::string finite = check_finite("confidence", value);
    if (!finite.empty())
        return finite;
    if (value > 0 && value < 1)
        return "";
    return "confidence must be between 0 and 1 (0 < confidence < 1), got " + format_number(value);
}

std::string check_blades(double value)
{
    if (std::isfinite(value) && is_whole(value) && value >= 3 && value <= kMaxBlades)
        return "";
    return "blades must be a whole number of iris blades from 3 to " + std::to_string(kMaxBlades) + ", got " +
           format_number(value);
}

std::string check_variance(double value)
{
    std::string finite = check_finite("variance", value);
    if (!finite.empty())
        return finite;
    if (value > 0)
        return "";
    return "variance must be positive (> 0), got " + format_number(value);
}

namespace {

// The thin lens: focal_length, f_number or aperture, focus_distance or distance.
std::string check_thin_lens(const MainLensParams& main, double mm_per_unit)
{
    if (main.has_prescription)
        return "main_lens thin_lens takes focal_length, not " + std::string(main.lens_file.empty() ? "a prescription" : "a lens_file") +
               ": leave thin_lens out to trace the real lens surface by surface, or write thick_lens for its "
               "paraxial equivalent";
    if (main.blades != 0)
        return "main_lens blades needs a real lens (lens_file or prescription { }); a thin_lens aperture is round";
    if (!main.has_focal_length)
        return "main_lens thin_lens needs focal_length (F in mm)";
    if (main.has_f_number && main.has_aperture)
        return "main_lens: give f_number or aperture, not both";
    if (!main.has_f_number && !main.has_aperture)
        return "main_lens thin_lens needs f_number or aperture (exactly one of the two)";
    if (!main.has_focus_distance && !main.has_distance)
        return "main_lens thin_lens needs focus_distance (scene units) or distance (D in mm)";
    if (main.has_f_number) {
        const double aperture = thin_lens_aperture_mm(main);  // F / N: the aperture is not given
        // The same range as a given aperture: beyond it the aperture's area overflows.
        if (!(aperture >= kMinLengthMm && aperture <= kMaxLengthMm))
            return "main_lens: focal_length " + format_number(main.focal_length_mm) + " mm / f_number " +
                   format_number(main.f_number) + " gives an aperture of " + format_number(aperture) +
                   " mm, outside " + format_number(kMinLengthMm) + " to " + format_number(kMaxLengthMm) + " mm";
    }
    if (main.has_focus_distance) {
        std::string scale = check_mm_per_unit(mm_per_unit);
        if (!scale.empty())
            return scale;
        const double z_mm = main.focus_distance_units * mm_per_unit;
        if (!(z_mm > main.focal_length_mm))
            return "focus_distance " + format_number(main.focus_distance_units) + " (" +
                   format_number(z_mm) + " mm at mm_per_unit " + format_number(mm_per_unit) +
                   ") is at or inside the focal length " + format_number(main.focal_length_mm) +
                   " mm; it must be greater than " + format_number(main.focal_length_mm / mm_per_unit) +
                   " scene units";
        const double D = main_lens_distance_mm(main, mm_per_unit);
        if (!(D >= kMinLengthMm && D <= kMaxLengthMm))
            return "main_lens: focus_distance " + format_number(main.focus_distance_units) + " puts the image "
                   "at D = F z / (z - F) = " + format_number(D) + " mm, outside " + format_number(kMinLengthMm) +
                   " to " + format_number(kMaxLengthMm) + " mm; focus farther from the focal length";
    }
    return "";
}

// A real lens (traced, or its thick lens): the prescription, its stop, its focus.
std::string check_real_lens(const MainLensParams& main, double mm_per_unit)
{
    const char* kind = main.type == MainLensType::ThickLens ? "main_lens thick_lens" : "main_lens";
    if (!main.has_prescription)
        return std::string(kind) + " needs the lens: lens_file \"name.dat\" or prescription { surface { ... } stop { ... } ... }";
    if (main.has_focal_length)
        return std::string(kind) + " takes no focal_length: a real lens's focal length follows from its surfaces";
    if (main.has_f_number && main.has_aperture)
        return "main_lens: give f_number or aperture, not both";
    if (main.blades != 0 && main.type == MainLensType::ThickLens)
        return "main_lens thick_lens takes no blades: its paraxial equivalent has a round exit pupil; leave thick_lens "
               "out to trace the iris";
    const PrescriptionError error = check_prescription(main.prescription);
    if (error.any())
        return "main_lens " + std::string(main.lens_file.empty() ? "prescription" : "lens_file \"" + main.lens_file + "\"") +
               (error.line > 0 ? " (line " + std::to_string(error.line) + ")" : "") + ": " + error.message;
    const ParaxialData bare = paraxial_data(main.prescription);
    if (!bare.valid)
        return "main_lens: the prescription forms no image (it is afocal, or its stop's image lies at infinity)";
    if (main.has_f_number) {
        const double stop = stop_diameter_for_f_number(main.prescription, main.f_number);
        if (!(stop >= kMinLengthMm && stop <= kMaxLengthMm))
            return "main_lens: f_number " + format_number(main.f_number) + " needs a stop diameter of " +
                   format_number(stop) + " mm, outside " + format_number(kMinLengthMm) + " to " +
                   format_number(kMaxLengthMm) + " mm";
    }
    if (!main.has_focus_distance && !main.has_distance)
        return std::string(kind) + " needs focus_distance (scene units from the front vertex) or distance "
               "(D in mm from the rear vertex)";
    if (main.has_focus_distance) {
        std::string scale = check_mm_per_unit(mm_per_unit);
        if (!scale.empty())
            return scale;
        const double z_mm = main.focus_distance_units * mm_per_unit;
        const ImageDistance image = paraxial_image_distance(main.prescription, z_mm);
        if (!image.real || !(image.mm >= kMinLengthMm && image.mm <= kMaxLengthMm))
            return "main_lens: the lens cannot focus at focus_distance " + format_number(main.focus_distance_units) +
                   " (" + format_number(z_mm) + " mm in front of its front vertex): the paraxial image lies " +
                   (image.real ? "at " + format_number(image.mm) + " mm behind the rear vertex, outside " +
                                     format_number(kMinLengthMm) + " to " + format_number(kMaxLengthMm) + " mm"
                               : std::string("at infinity or in front of the rear vertex")) +
                   "; the front focal point is " + format_number(bare.ffd_mm) + " mm in front of the front vertex "
                   "(focal length " + format_number(bare.efl_mm) + " mm): focus farther than that";
    }
    const double D = main_lens_distance_mm(main, mm_per_unit);
    // The exit pupil of the aperture that limits the axial beam to z = -D (the stop's, unless a
    // rim limits it: then the reach check below, or a warning when the stop is as written).
    const ParaxialData at_d = paraxial_data(effective_prescription(main), 0, D);
    if (!at_d.valid)
        return "main_lens: the aperture that limits the lens's axial beam (" +
               describe_surface(main.prescription, at_d.aperture_surface, main.lens_file) + ") images at infinity";
    const double pupil_behind = at_d.exit_pupil_z - at_d.rear_vertex_z;
    if (!(D > pupil_behind))
        return "main_lens: the array (or sensor) at D = " + format_number(D) + " mm behind the rear vertex lies in "
               "front of the lens's exit pupil, " + format_number(pupil_behind) + " mm behind the rear vertex; "
               "the image side of a lens starts there";
    return check_aperture_reach(main, mm_per_unit);
}

} // namespace

std::string format_rounded(double value, bool round_up)
{
    if (!(value > 0) || !std::isfinite(value))
        return format_number(value);
    const double scale = std::pow(10.0, 3 - std::floor(std::log10(value)));
    const double rounded = (round_up ? std::ceil(value * scale - 1e-9) : std::floor(value * scale + 1e-9)) / scale;
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%.4g", rounded);
    return buffer;
}

std::string describe_surface(const Prescription& lens, int index, const std::string& lens_file)
{
    if (index < 0 || index >= int(lens.surfaces.size()))
        return "no surface";
    const LensSurface& s = lens.surfaces[size_t(index)];
    std::string where;
    if (s.line > 0)
        where = lens_file.empty() ? "scene line " + std::to_string(s.line)
                                  : "line " + std::to_string(s.line) + " of lens_file \"" + lens_file + "\"";
    const std::string number = "surface " + std::to_string(index + 1);
    if (s.stop)
        return "the stop (" + number + (where.empty() ? "" : ", " + where) + ")";
    return number + (where.empty() ? "" : " (" + where + ")");
}

std::string check_aperture_reach(const MainLensParams& main, double mm_per_unit)
{
    if (!is_prescription_type(main.type) || !(main.has_f_number || main.has_aperture) || !main.has_prescription)
        return "";
    const Prescription lens = effective_prescription(main);
    const double D = main_lens_distance_mm(main, mm_per_unit);
    const ParaxialData p = paraxial_data(lens, 0, D);
    if (!p.valid || p.aperture_surface < 0 || lens.surfaces[size_t(p.aperture_surface)].stop)
        return "";
    const std::string asked = main.has_f_number ? "f_number " + format_number(main.f_number)
                                                : "aperture " + format_number(main.aperture_mm);
    const LensSurface& rim = lens.surfaces[size_t(p.aperture_surface)];
    std::string message = "main_lens: " + asked + " asks for a stop " + format_rounded(p.stop_mm, false) +
                          " mm wide, which this lens cannot deliver: at that size a clear aperture, not the stop, "
                          "limits the beam to the array's (or sensor's) axial point: " +
                          describe_surface(lens, p.aperture_surface, main.lens_file) + ", clear aperture " +
                          format_number(rim.aperture_mm) + " mm";
    if (p.largest_stop_mm > 0 && std::isfinite(p.largest_stop_mm))
        message += "; the fastest f-number the lens reaches is " +
                   format_rounded(f_number_for_stop_diameter(main.prescription, p.largest_stop_mm), true) +
                   ", with a stop (aperture) of at most " + format_rounded(p.largest_stop_mm, false) + " mm";
    else
        message += "; the stop lies where the axial beam has no width and never limits it (the lens works at f/" +
                   format_rounded(p.f_number, true) + " without f_number or aperture)";
    return message;
}

CameraParams at_f_number(const CameraParams& params, double f_number)
{
    CameraParams p = params;
    p.main.has_f_number = true;
    p.main.f_number = f_number;
    p.main.has_aperture = false;
    p.main.aperture_mm = 0;
    return p;
}



std::string check_main_lens(const MainLensParams& main, double mm_per_unit)
{
    if (!main.given)
        return "";
    if (main.type == MainLensType::None)
        return "main_lens needs thin_lens, pinhole, or a real lens (lens_file \"name.dat\" or prescription { }, "
               "with thick_lens for its paraxial equivalent)";

    // Values again: a backstop for a caller that filled the struct without the token checks.
    std::string message;
    if (main.has_focal_length && !(message = check_positive_length("focal_length", main.focal_length_mm)).empty())
        return message;
    if (main.has_f_number && !(message = check_f_number(main.f_number)).empty())
        return message;
    if (main.has_aperture && !(message = check_positive_length("aperture", main.aperture_mm)).empty())
        return message;
    if (main.has_focus_distance && !(message = check_focus_distance(main.focus_distance_units)).empty())
        return message;
    if (main.has_distance && !(message = check_positive_length("distance", main.distance_mm)).empty())
        return message;
    if (main.blades != 0 && !(message = check_blades(main.blades)).empty())
        return message;
    if (!(message = check_angle("blade_rotation", main.blade_rotation_deg)).empty())
        return message;

    if (main.has_focus_distance && main.has_distance)
        return "main_lens: give focus_distance or distance, not both";
    if (main.has_distortion) {
        if (main.type != MainLensType::ThinLens)
            return std::string("main_lens distortion { } models a thin_lens's distortion; ") +
                   (main.type == MainLensType::Pinhole ? "a pinhole has none"
                                                       : "a real lens has the distortion of its surfaces");
        // Rays are mapped out to 45 degrees from the lens centre on the image side (normalised
        // radius 1), beyond any plenoptic camera's field.
        if (!(message = check_distortion(main.distortion, 1.0)).empty())
            return message;
    }

    if (main.type == MainLensType::Pinhole) {
        // A pinhole has no focal length, so neither can it focus nor have an f-number.
        if (main.has_prescription)
            return "main_lens pinhole takes no lens_file or prescription; give distance (D in mm) only";
        if (main.blades != 0)
            return "main_lens pinhole takes no blades (a pinhole has no iris); give distance (D in mm) only";
        if (main.has_focal_length)
            return "main_lens pinhole takes no focal_length (a pinhole has no focal length); "
                   "give distance (D in mm) only";
        if (main.has_f_number)
            return "main_lens pinhole takes no f_number (a pinhole has no aperture to size); "
                   "give distance (D in mm) only";
        if (main.has_aperture)
            return "main_lens pinhole takes no aperture (a pinhole has no aperture to size); "
                   "give distance (D in mm) only";
        if (main.has_focus_distance)
            return "main_lens pinhole takes distance (D in mm), not focus_distance: "
                   "a pinhole has no focal length to focus with";
        if (!main.has_distance)
            return "main_lens pinhole needs distance (D: main lens to microlens array, "
                   "or to the sensor when there is no array, in mm)";
        return "";
    }
    if (main.type == MainLensType::ThinLens)
        return check_thin_lens(main, mm_per_unit);
    return check_real_lens(main, mm_per_unit);
}

std::string check_microlens_ior(const char* keyword, double value)
{
    if (!(value > 1 && value <= kMaxMicrolensIor))
        return str(keyword) + " is the index of refraction of the microlenses' glass, greater than 1 and at most " +
               format_number(kMaxMicrolensIor) + ", got " + format_number(value);
    return "";
}

std::string check_microlens_conic(const char* keyword, double value)
{
    if (!(value >= kMinMicrolensConic && value <= kMaxMicrolensConic))
        return str(keyword) + " is the cap's conic constant, from " + format_number(kMinMicrolensConic) + " to " +
               format_number(kMaxMicrolensConic) + ", got " + format_number(value);
    return "";
}

// The largest deviation of a lens's focal length from its type's, drawn (4 standard deviations of
// at most 0.05) or tabled.
const double kMaxFocalDeviation = 0.2;

// The cap of surface radius `radius` (conic and thickness as written) over its cell: "" or what is
// wrong with it (with `height`, also a cap that rises more than its thickness).
static std::string check_cap(const ArrayParams& array, double radius, bool height_too = true)
{
    const RefractingShape& s = array.refracting;
    RefractingShape shape = s;
    shape.radius_mm = radius;
    const double corner = cell_circumradius(array.grid, array.pitch_mm);
    const char* grid = array.grid == GridType::Hexagonal ? "hexagonal" : "rectangular";
    // The cap's surface must exist over the whole cell: a sphere out to its radius, a conic out to
    // R / sqrt(1 + k) (k > -1).
    const double reach = s.conic > -1 ? radius / std::sqrt(1 + s.conic) : INFINITY;
    if (!(reach > corner))
        return "surface radius " + format_number(radius) + " mm" +
               (s.conic != 0 ? " with conic " + format_number(s.conic) + " (the surface ends " +
                               format_number(reach) + " mm from the axis)" : std::string()) +
               " does not cover the lens's cell: its corners are " + format_number(corner) + " mm from the centre (" +
               grid + " pitch " + format_number(array.pitch_mm) + " mm); the radius must exceed that (a flatter cap)";
    const double height = shape.sag(corner * corner);
    if (height_too && !(height <= s.cap_mm))
        return "the cap rises " + format_number(height) + " mm from its cell's corners to its vertex (surface radius " +
               format_number(radius) + " mm over " + format_number(corner) + " mm), more than its thickness " +
               format_number(s.cap_mm) + " mm; give thickness at least that, or a larger radius";
    return "";
}

std::string check_refracting_shape(const ArrayParams& array)
{
    const RefractingShape& s = array.refracting;
    if (array.fill_factor != 1 || array.mask)
        return "microlens_array fill_factor and mask are not modelled for refracting microlenses (lens { }): their "
               "caps fill their cells";
    std::string message = check_cap(array, s.radius_mm);
    if (!message.empty())
        return "microlens_array lens " + message;
    // A lens whose focal length is e times the cap's has its radius scaled by e (array/
    // refracting_microlens.cpp): the smallest such cap must cover its cell too (its surface must
    // exist out to the cell's corners; the thickness is the written cap's, checked above).
    // (A deviation beyond the drawn errors' limit is refused by check_array_errors, naming it.)
    if (array.has_errors && array.errors.focal_sd > 0 && array.errors.focal_sd < kMaxFocalDeviation / kErrorSigmas) {
        const double smallest = 1 - kErrorSigmas * array.errors.focal_sd;
        message = check_cap(array, s.radius_mm * smallest, false);
        if (!message.empty())
            return "microlens_array errors focal_length " + format_number(array.errors.focal_sd) +
                   ": a lens drawn at " + format_number(smallest) + " times the cap's focal length (the draws go to " +
                   format_number(kErrorSigmas) + " standard deviations), whose radius scales with it: " + message +
                   "; give a smaller focal_length error or a flatter cap";
    } else if (array.lens_table) {
        for (const LensTableRow& row : *array.lens_table) {
            if (!(row.focal_length_mm > 0))
                continue;
            message = check_cap(array, s.radius_mm * row.focal_length_mm / s.focal_length_mm(), false);
            if (!message.empty())
                return "microlens_array lens_table \"" + array.lens_table_file + "\": lens (" +
                       std::to_string(row.lens.k) + ", " + std::to_string(row.lens.l) + ") of focal_length_mm " +
                       format_number(row.focal_length_mm) + " (the cap's own is " + format_number(s.focal_length_mm()) +
                       " mm; its radius scales with it): " + message;
        }
    }
    return "";
}

std::string check_array(const ArrayParams& array)
{
    if (!array.given)
        return "";
    if (array.grid == GridType::None)
        return "microlens_array needs rectangular or hexagonal";
    if (!array.has_pitch)
        return "microlens_array needs pitch (lens centre to centre, mm)";
    std::string message = check_positive_length("pitch", array.pitch_mm);
    if (!message.empty())
        return message;
    if (!array.has_lens)
        return "microlens_array needs focal_length, focal_lengths, pinhole or lens { }";
    if (array.lens == MicrolensType::Refracting) {
        message = check_refracting_shape(array);
        if (!message.empty())
            return message;
    }
    if (array.lens == MicrolensType::Pinhole && array.focal_length_count != 0)
        return "microlens_array: give pinhole or focal_length(s), not both";
    if (array.lens == MicrolensType::ThinLens && array.focal_length_count != 1 && array.focal_length_count != 3)
        return "microlens_array focal_lengths must have exactly 3 values (one per lens type), got " +
               std::to_string(array.focal_length_count);
    if (array.focal_length_count == 3 && array.grid != GridType::Hexagonal)
        return "microlens_array focal_lengths (three interleaved lens types) needs a hexagonal grid; "
               "a rectangular grid takes a single focal_length";
    for (int i = 0; i < array.focal_length_count; ++i) {
        message = check_positive_length(array.focal_length_count == 1 ? "focal_length" : "focal_lengths",
                                        array.focal_lengths_mm[i]);
        if (!message.empty())
            return message;
    }
    if (array.abbe != 0) {
        if (array.lens == MicrolensType::Pinhole)
            return "microlens_array abbe " + format_number(array.abbe) +
                   ": a pinhole has no glass to disperse; abbe goes with focal_length or focal_lengths";
        message = check_abbe(array.abbe);
        if (!message.empty())
            return "microlens_array abbe: " + message;
    }
    if (!array.has_distance)
        return "microlens_array needs distance (d: microlens array to sensor, mm)";
    message = check_positive_length("distance", array.distance_mm);
    if (!message.empty())
        return message;
    for (int i = 0; i < 3; ++i) {
        if (!(message = check_angle("rotate", array.rotate_deg[i])).empty())
            return message;
        if (!(message = check_translation("translate", array.translate_mm[i])).empty())
            return message;
    }
    return check_array_errors(array);
}

std::string check_error_deviation(const char* keyword, double value)
{
    if (!(value >= 0))
        return std::string(keyword) + " " + format_number(value) + " must be zero or positive (a standard deviation)";
    return "";
}

std::string check_error_rotation(double degrees)
{
    if (!(degrees >= 0 && degrees < 30))
        return "errors rotation " + format_number(degrees) + " must be in [0, 30) degrees (the largest tilt of a lens's axis)";
    return "";
}

std::string check_fill_factor(double value)
{
    if (!(value > 0 && value <= 1))
        return "microlens_array fill_factor " + format_number(value) +
               " must be in (0, 1] (the part of each cell that is lens)";
    return "";
}

std::string check_array_errors(const ArrayParams& array)
{
    const bool pinholes = array.lens == MicrolensType::Pinhole;
    if (array.has_errors && !array.lens_table_file.empty())
        return "microlens_array takes errors { } or lens_table, not both";
    if (array.has_errors) {
        const ErrorSpec& e = array.errors;
        // Every lens within a quarter pitch of its lattice point (kErrorSigmas standard deviations),
        // so that a lens is found from its lattice cell and its neighbours.
        const double largest = array.pitch_mm / (4 * kErrorSigmas * std::sqrt(2.0));
        if (!(e.position_sd_mm < largest))
            return "errors position " + format_number(e.position_sd_mm) + " must be below " + format_number(largest) +
                   " mm for pitch " + format_number(array.pitch_mm) + " mm (pitch / (16 sqrt 2): every lens within a quarter "
                   "pitch of its lattice point)";
        if (!(e.position_sd_z_mm < array.pitch_mm / (4 * kErrorSigmas)))
            return "errors position: S_z " + format_number(e.position_sd_z_mm) + " must be below " +
                   format_number(array.pitch_mm / (4 * kErrorSigmas)) + " mm (pitch / 16)";
        if (!(e.focal_sd < kMaxFocalDeviation / kErrorSigmas))
            return "errors focal_length " + format_number(e.focal_sd) + " must be below " +
                   format_number(kMaxFocalDeviation / kErrorSigmas) + " (a relative standard deviation: 0.01 is 1 %)";
        if (pinholes && (e.focal_sd > 0 || e.rotation_deg > 0))
            return "errors focal_length and rotation need microlenses that form an image (pinholes have neither a focal "
                   "length nor an axis): use position only";
    }
    if (!array.lens_table_file.empty() && pinholes && array.lens_table)
        for (const LensTableRow& row : *array.lens_table)
            if (row.focal_length_mm > 0 || row.error.tilt_deg > 0)
                return "lens_table \"" + array.lens_table_file + "\": lens (" + std::to_string(row.lens.k) + ", " +
                       std::to_string(row.lens.l) + ") has a focal length or a tilt, which pinholes do not have";
    if (!array.lens_table_file.empty() && !pinholes && array.lens_table) {
        // A measured focal length within the drawn errors' reach of its type's.
        const double largest = kMaxFocalDeviation;
        for (const LensTableRow& row : *array.lens_table) {
            if (!(row.focal_length_mm > 0))
                continue;
            const int types = array.lens == MicrolensType::ThinLens ? array.focal_length_count : 1;
            const double type_focal = array.lens == MicrolensType::Refracting
                                          ? array.refracting.focal_length_mm()
                                          : array.focal_lengths_mm[types == 1 ? 0 : lens_type(row.lens, types)];
            const double factor = row.focal_length_mm / type_focal;
            if (!(std::fabs(factor - 1) <= largest))
                return "lens_table \"" + array.lens_table_file + "\": lens (" + std::to_string(row.lens.k) + ", " +
                       std::to_string(row.lens.l) + ") has focal_length_mm " + format_number(row.focal_length_mm) +
                       ", " + format_number(factor) + " times its type's " + format_number(type_focal) +
                       " mm; a lens's focal length must lie within " + format_number(100 * largest) +
                       " % of its type's (as drawn errors do)";
        }
    }
    if (array.fill_factor != 1 || array.mask) {
        if (pinholes)
            return "microlens_array fill_factor and mask need microlenses that form an image (a pinhole passes light "
                   "at its centre only)";
        const std::string message = check_fill_factor(array.fill_factor);
        if (!message.empty())
            return message;
    }
    return "";
}

std::string check_angular_exponent(double value)
{
    if (!std::isfinite(value))
        return "angular_response must be a finite number, got " + format_number(value);
    if (!(value >= 0 && value <= kMaxAngularExponent))
        return "angular_response is the exponent n of cos^n(incidence angle), from 0 to " +
               format_number(kMaxAngularExponent) + ", got " + format_number(value);
    return "";
}

std::string check_sensor(const SensorParams& sensor)
{
    std::string message;
    for (int i = 0; i < 2; ++i) {
        if (!(message = check_positive_length("pixel_size", sensor.pixel_size_mm[i])).empty())
            return message;
        if (!(message = check_translation("offset", sensor.offset_mm[i])).empty())
            return message;
    }
    if (!(message = check_angular_exponent(sensor.angular_exponent)).empty())
        return message;
    return sensor.chain.given ? check_sensor_chain(sensor.chain) : "";
}

// The adaptive form tests the variance of the samples taken so far; one sample has none, so a
// minimum of 1 would stop every pixel after its first ray (focal_blur's rule needs several too).
std::string check_adaptive_minimum(double value)
{
    if (value < 2)
        return "samples: the adaptive form samples MIN, MAX needs a minimum of at least 2 (got " +
               format_number(value) + "): one sample has no variance to test; write samples N for a fixed count";
    return "";
}

std::string check_sampling(const SamplingParams& sampling)
{
    std::string message;
    if (!sampling.adaptive)
        return sampling.samples == kSamplesOmitted ? std::string() : check_samples("samples", sampling.samples);
    if (!(message = check_samples("samples (minimum)", sampling.samples_min)).empty())
        return message;
    if (!(message = check_adaptive_minimum(sampling.samples_min)).empty())
        return message;
    if (!(message = check_samples("samples (maximum)", sampling.samples_max)).empty())
        return message;
    if (sampling.samples_max < sampling.samples_min)
        return "samples: the maximum (" + std::to_string(sampling.samples_max) +
               ") must not be less than the minimum (" + std::to_string(sampling.samples_min) + ")";
    if (!(message = check_confidence(sampling.confidence)).empty())
        return message;
    return check_variance(sampling.variance);
}

std::string check_spectral(const SpectralParams& spectral)
{
    if (!spectral.given())
        return "";
    std::string message = check_spectral_bands(spectral.bands);
    if (!message.empty())
        return message;
    if (spectral.response.tabulated && spectral.gaussian_written)
        return "spectral takes response_file or response_centres / response_widths (Gaussian sensitivities), not both";
    return check_response(spectral.response);
}

std::string check_camera(const CameraParams& camera)
{
    std::string message;
    if (!(message = check_mm_per_unit(camera.mm_per_unit)).empty())
        return message;
    if (!(message = check_main_lens(camera.main, camera.mm_per_unit)).empty())
        return message;
    if (!(message = check_array(camera.array)).empty())
        return message;
    if (!(message = check_sensor(camera.sensor)).empty())
        return message;
    if (!(message = check_sampling(camera.sampling)).empty())
        return message;
    if (!(message = check_spectral(camera.spectral)).empty())
        return message;

    if (camera.sensor.angular_exponent > 0 && camera.radiometry != Radiometry::Irradiance)
        return "sensor angular_response weights the light a pixel receives by its angle of incidence: it needs "
               "radiometry irradiance (flat radiometry is the stock cameras' picture, which has no such response)";
    const bool has_main = camera.main.given;
    const bool has_array = camera.array.given;
    if (!has_main && !has_array)
        return "plenoptic camera needs a main_lens block, a microlens_array block, or both";
    if (!has_array)
        return "";

    const ArrayParams& array = camera.array;
    if (camera.radiometry == Radiometry::Irradiance && has_main && camera.main.type == MainLensType::Pinhole &&
        array.lens == MicrolensType::ThinLens)
        return "radiometry irradiance needs a main lens with an area when the microlenses are lenses: behind a "
               "pinhole main_lens each microlens focuses the pinhole's light onto a point, whose irradiance depends "
               "on the pinhole's size, which the camera does not have; use a thin_lens main lens, pinhole "
               "microlenses, or radiometry flat";
    if (has_main && camera.main.type == MainLensType::Pinhole && array.lens == MicrolensType::Refracting)
        return "a pinhole main_lens with refracting microlenses (microlens_array lens { }) is not supported: behind a "
               "pinhole each sensor point sees the one ray through the pinhole, which the exact trace through the caps "
               "has no closed form for; use a thin_lens or real main lens, or thin microlenses (focal_length)";
    if (has_main && camera.main.type == MainLensType::Pinhole && array.lens == MicrolensType::Pinhole)
        return "a pinhole main_lens with a pinhole microlens_array is degenerate: no light reaches the "
               "sensor (a ray would have to pass two points and the pixel at once); make one of them "
               "a thin lens";

    const Mat3 rotation = rotation_from_degrees(array.rotate_deg);
    // The array's normal must face the scene; edge-on or reversed arrays pass no light.
    if (!(rotation.m[2][2] > 0))
        return "microlens_array rotate <" + format_number(array.rotate_deg[0]) + ", " +
               format_number(array.rotate_deg[1]) + ", " + format_number(array.rotate_deg[2]) +
               "> turns the array edge-on or backwards; its tilt about x and y must stay below 90 degrees";

    // The array must stay between the main lens and the sensor (at its centre).
    const double tz = array.translate_mm[2];
    const double d_eff = array.distance_mm + tz;
    if (!(d_eff > 0))
        return "microlens_array translate z = " + format_number(tz) + " mm moves the array onto or behind "
               "the sensor (distance d = " + format_number(array.distance_mm) + " mm)";
    if (!has_main)
        return "";

    const double main_distance = main_lens_distance_mm(camera.main, camera.mm_per_unit);
    // The sensor must stay a separate plane from the array in double precision.
    if (!((main_distance + d_eff) - main_distance > 0.5 * d_eff))
        return "microlens_array distance d = " + format_number(d_eff) + " mm is too small beside D = " +
               format_number(main_distance) + " mm: the sensor would coincide with the array";
    const double main_eff = main_distance - tz;
    if (!(main_eff > 0))
        return "microlens_array translate z = " + format_number(tz) + " mm moves the array onto or in front "
               "of the main lens (distance D = " + format_number(main_distance) + " mm)";
    if (is_prescription_type(camera.main.type)) {
        const ParaxialData p = paraxial_data(effective_prescription(camera.main), 0, main_distance);
        const double pupil_behind = p.exit_pupil_z - p.rear_vertex_z;  // exit pupil behind the rear vertex (mm)
        if (!(main_eff > pupil_behind))
            return "microlens_array at " + format_number(main_eff) + " mm behind the lens's rear vertex lies in front "
                   "of its exit pupil (" + format_number(pupil_behind) + " mm behind the rear vertex), from which "
                   "microimage centres are projected; move the array farther back";
    }

    // Pinhole main lens: a thin microlens that images the sensor plane onto the pinhole sends every
    // ray from a sensor point back to that point, so only one point per microimage would be lit.
    const bool tilted = !(rotation.m[0][2] == 0 && rotation.m[1][2] == 0);
    if (camera.main.type == MainLensType::Pinhole && array.lens == MicrolensType::ThinLens && !tilted) {
        for (int i = 0; i < array.focal_length_count; ++i) {
            const double f = array.focal_lengths_mm[i];
            const double g = 1.0 + main_eff / d_eff - main_eff / f;
            const double scale = 1.0 + main_eff / d_eff + main_eff / f;
            if (std::fabs(g) <= 1e-12 * scale)
                return "pinhole main_lens with microlens focal length " + format_number(f) +
                       " mm at D = " + format_number(main_eff) + " mm and d = " + format_number(d_eff) +
                       " mm is degenerate: the microlenses image the sensor onto the pinhole "
                       "(1/D + 1/d = 1/f), so no light reaches the sensor; change distance or focal_length";
        }
    }
    return "";
}

std::string check_placement(const double right[3], const double up[3], const double direction[3])
{
    const double* axes[3] = {right, up, direction};
    const char* names[3] = {"right", "up", "direction"};
    double unit[3][3];
    for (int a = 0; a < 3; ++a) {
        const double length = std::sqrt(axes[a][0] * axes[a][0] + axes[a][1] * axes[a][1] + axes[a][2] * axes[a][2]);
        if (!std::isfinite(length) || !(length > 0))
            return std::string("the camera's ") + names[a] + " vector has length " + format_number(length) +
                   ": right, up and direction must be finite and non-zero";
        for (int c = 0; c < 3; ++c)
            unit[a][c] = axes[a][c] / length;
    }
    const double volume = unit[0][0] * (unit[1][1] * unit[2][2] - unit[1][2] * unit[2][1]) -
                          unit[0][1] * (unit[1][0] * unit[2][2] - unit[1][2] * unit[2][0]) +
                          unit[0][2] * (unit[1][0] * unit[2][1] - unit[1][1] * unit[2][0]);
    if (!(std::fabs(volume) >= 1e-9))
        return "the camera's right, up and direction vectors are parallel or lie in one plane (their unit "
               "vectors' triple product is " + format_number(volume) + "): they must span 3-D space";
    return "";
}

int default_samples(const CameraParams& camera)
{
    const bool thin_microlenses = camera.array.given && (camera.array.lens == MicrolensType::ThinLens ||
                                                         camera.array.lens == MicrolensType::Refracting);
    const bool bare_thin_main = !camera.array.given && camera.main.given && camera.main.type != MainLensType::Pinhole;
    return thin_microlenses || bare_thin_main ? kDefaultSamplesApertures : kDefaultSamplesPinholes;
}

} // namespace plenoptic
