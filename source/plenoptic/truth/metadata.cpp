// SPDX-License-Identifier: AGPL-3.0-or-later
// Writes the plenoptic render metadata (docs/metadata.md) with nlohmann-json: the document is
// built as an ordered_json (members in the documented order), every number and string is
// serialised by the library; only the line layout is chosen here.

#include "plenoptic/truth/metadata.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <nlohmann/json.hpp>

#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/truth/distortion_profile.h"
#include "plenoptic/optics.h"
#include "plenoptic/camera/radiometry.h"

namespace plenoptic {

namespace {

using Json = nlohmann::ordered_json;

// Field heights of the distortion profile, 0 to the picture's corner in sixteenths.
const int kDistortionProfileSamples = 17;

// A finite number, or null (JSON has no NaN or infinity). Whole numbers below 2^53 are stored as
// integers so that they print without a fraction ("1000", not "1000.0"; -0 as 0); every other
// value prints in the library's shortest form that reads back to the same double (0.15, not
// 0.14999999999999999).
Json number(double value)
{
    if (!std::isfinite(value))
        return nullptr;
    if (value == std::floor(value) && std::fabs(value) < 9007199254740992.0)
        return Json(static_cast<std::int64_t>(value));
    return Json(value);
}

Json number_or_null(bool present, double value) { return present ? number(value) : Json(nullptr); }

Json numbers(const double* values, int count)
{
    Json array = Json::array();
    for (int i = 0; i < count; ++i)
        array.push_back(number(values[i]));
    return array;
}

// Strings that are not UTF-8 (a file name in Latin-1, say) cannot be JSON text: each invalid byte
// becomes U+FFFD.
std::string scalar_text(const Json& value)
{
    return value.dump(-1, ' ', false, Json::error_handler_t::replace);
}

// Objects one member per line, indented by two spaces a level; arrays, and the short object
// "samples", on one line (the layout docs/metadata.md shows).
void layout(const Json& value, int depth, bool one_line, std::string* out)
{
    const bool object = value.is_object();
    if (!object && !value.is_array()) {
        *out += scalar_text(value);
        return;
    }
    *out += object ? '{' : '[';
    bool first = true;
    for (auto it = value.begin(); it != value.end(); ++it) {
        if (!first)
            *out += one_line ? ", " : ",";
        first = false;
        if (!one_line) {
            *out += '\n';
            out->append(2 * (depth + 1), ' ');
        }
        bool inline_child = one_line || it->is_array();
        if (object) {
            *out += scalar_text(Json(it.key())) + ": ";
            inline_child = inline_child || it.key() == "samples";
        }
        layout(*it, depth + 1, inline_child, out);
    }
    if (!one_line && !first) {
        *out += '\n';
        out->append(2 * depth, ' ');
    }
    *out += object ? '}' : ']';
}

// The surfaces as the render used them (the stop at its working diameter), object side first.
Json prescription_json(const PlenopticCamera& m)
{
    Json surfaces = Json::array();
    for (const LensSurface& s : m.prescription().surfaces) {
        Json row = Json::object();
        row["stop"] = s.stop;
        row["radius_mm"] = number(s.radius_mm);
        row["thickness_mm"] = number(s.thickness_mm);
        row["ior"] = number(s.ior);
        row["aperture_mm"] = number(s.aperture_mm);
        surfaces.push_back(row);
    }
    Json json = Json::object();
    json["lens_file"] = m.lens_file().empty() ? Json(nullptr) : Json(m.lens_file());
    json["blades"] = m.prescription().blades;
    json["blade_rotation_deg"] = number(m.prescription().blade_rotation_deg);
    json["surfaces"] = surfaces;
    return json;
}

// First-order data in the optics frame (z from the rear vertex towards the scene, mm).
Json paraxial_json(const PlenopticCamera& m)
{
    const ParaxialData& p = m.paraxial();
    const double length = m.lens_length_mm();
    const double exit_pupil_z = length - p.exit_pupil_z;
    Json json = Json::object();
    json["effective_focal_length_mm"] = number(p.efl_mm);
    json["back_focal_distance_mm"] = number(p.bfd_mm);
    json["front_focal_distance_mm"] = number(p.ffd_mm);
    json["length_mm"] = number(length);
    json["front_vertex_z_mm"] = number(length);
    json["front_principal_plane_z_mm"] = number(length - p.front_principal_z);
    json["rear_principal_plane_z_mm"] = number(length - p.rear_principal_z);
    json["entrance_pupil_z_mm"] = number(length - p.entrance_pupil_z);
    json["entrance_pupil_diameter_mm"] = number(p.entrance_pupil_mm);
    json["exit_pupil_z_mm"] = number(exit_pupil_z);
    json["exit_pupil_diameter_mm"] = number(p.exit_pupil_mm);
    json["f_number"] = number(p.f_number);
    // Image side, as f-number matching needs it: exit pupil to the array (or sensor) over its diameter.
    json["working_f_number"] = number((exit_pupil_z + m.distance_mm) / p.exit_pupil_mm);
    // The aperture the pupils image (index into prescription.surfaces: the stop's, unless a rim
    // limits the axial beam), and the widest stop that still limits it (null: no rim ever does).
    json["limiting_surface"] = p.aperture_surface;
    json["largest_stop_diameter_mm"] = number(p.largest_stop_mm);
    return json;
}

// The chief ray's image height over the field against the paraxial one (null when the lens has
// no profile).
Json distortion_profile_json(const PlenopticCamera& m)
{
    const DistortionProfile profile = distortion_profile(m, kDistortionProfileSamples);
    if (!profile.valid)
        return nullptr;
    Json json = Json::object();
    json["object_plane_z_mm"] = profile.object_at_infinity ? Json(nullptr) : number(profile.object_plane_z_mm);
    json["image_plane_z_mm"] = number(profile.image_plane_z_mm);
    json["chief_ray"] = m.lens->chief_ray_description();
    json["columns"] = Json::array({"relative_field", "field_angle_deg", "paraxial_height_mm", "real_height_mm", "distortion_percent"});
    Json samples = Json::array();
    for (const DistortionSample& s : profile.samples) {
        const double percent = s.paraxial_height_mm > 0 ? 100 * (s.real_height_mm / s.paraxial_height_mm - 1) : NAN;
        samples.push_back(Json::array({number(s.relative_field), number(s.field_angle_deg), number(s.paraxial_height_mm),
                                       number(s.real_height_mm), number(percent)}));
    }
    json["samples"] = samples;
    return json;
}

Json main_lens(const PlenopticCamera& m)
{
    const bool has_focal = m.lens && m.lens->forms_image();
    Json json = Json::object();
    json["type"] = m.lens ? m.lens->kind_name() : "none";
    json["focal_length_mm"] = number_or_null(has_focal, m.focal_length_mm());
    json["aperture_mm"] = number_or_null(has_focal, m.aperture_mm());
    json["f_number"] = number_or_null(has_focal, m.f_number());
    json["distance_mm"] = number_or_null(bool(m.lens), m.distance_mm);
    json["focus_distance"] = number_or_null(m.has_focus_distance, m.focus_distance_units);
    if (m.lens && m.lens->prescription()) {
        json["prescription"] = prescription_json(m);
        json["paraxial"] = paraxial_json(m);
    }
    if (const DistortionParams* given = m.distortion()) {
        // Radial-tangential polynomial on the plane z = -D, coordinates (x, y) / D.
        Json distortion = Json::object();
        distortion["radial"] = numbers(given->radial, 3);
        distortion["tangential"] = numbers(given->tangential, 2);
        distortion["plane_z_mm"] = number(-m.distance_mm);
        json["distortion"] = distortion;
    }
    json["distortion_profile"] = distortion_profile_json(m);
    return json;
}

Json microlens_array(const PlenopticCamera& m, const CameraParams& params)
{
    if (m.array.grid == GridType::None)
        return nullptr;
    Json json = Json::object();
    json["grid"] = m.array.grid == GridType::Hexagonal ? "hexagonal" : "rectangular";
    json["lens"] = m.array.microlens == MicrolensType::ThinLens ? "thin_lens" : "pinhole";
    json["pitch_mm"] = number(m.array.pitch_mm);
    json["focal_lengths_mm"] =
        numbers(m.array.focal_mm, m.array.microlens == MicrolensType::ThinLens ? m.array.lens_type_count : 0);
    json["distance_mm"] = number(m.array.distance_mm);
    json["rotate_deg"] = numbers(params.array.rotate_deg, 3);
    json["translate_mm"] = numbers(params.array.translate_mm, 3);
    return json;
}

Json lattice_json(const PlenopticCamera& m, const MicroimageLattice& lattice)
{
    if (!lattice.valid)
        return nullptr;
    const bool hexagonal = m.array.grid == GridType::Hexagonal;
    Json json = Json::object();
    json["origin_px"] = numbers(lattice.origin_px, 2);
    json["basis_px"] = Json::array({numbers(lattice.basis_a_px, 2), numbers(lattice.basis_b_px, 2)});
    json["index_rule"] = hexagonal
                             ? "skew indices (k, l): hexagonal centres in the array are k*(p,0) + l*(p/2, p*sqrt(3)/2)"
                             : "skew indices (k, l): rectangular centres in the array are k*(p,0) + l*(0,p)";
    json["exact"] = lattice.exact;
    const int types = m.array.microlens == MicrolensType::ThinLens ? m.array.lens_type_count : 1;
    json["lens_types"] = types;
    json["lens_type_rule"] = types == 3 ? "type(k, l) = (k - l) mod 3, focal_lengths_mm[type]" : "type(k, l) = 0";
    // Diameter of the main lens's exit pupil imaged through a lens centre (the f-number-matched disc).
    const bool has_pupil = m.lens && m.lens->forms_image();
    const double pupil_mm = has_pupil ? 2 * m.lens->exit_pupil_radius() : 0;  // a thin lens's: A (2 * A/2, exact)
    json["microimage_diameter_px"] =
        number_or_null(has_pupil, pupil_mm * effective_array_distance_mm(m) / effective_main_distance_mm(m) / m.sensor.pixel_size_mm[0]);
    return json;
}

Json lftoolbox(const MicroimageLattice& lattice)
{
    if (!lattice.valid || !lattice.lftoolbox_valid)
        return nullptr;
    Json json = Json::object();
    json["HSpacing"] = number(lattice.h_spacing);
    json["VSpacing"] = number(lattice.v_spacing);
    json["HOffset"] = number(lattice.h_offset);
    json["VOffset"] = number(lattice.v_offset);
    json["Rot"] = number(lattice.rot);
    json["Orientation"] = "horz";
    // Rectangular grid: null, LFToolbox's grid always shifts alternate rows.
    json["FirstPosShiftRow"] = lattice.first_pos_shift_row > 0 ? Json(lattice.first_pos_shift_row) : Json(nullptr);
    json["UMax"] = lattice.u_max;
    json["VMax"] = lattice.v_max;
    return json;
}

Json microimages_json(const MicroimageSummary* summary)
{
    if (summary == nullptr)
        return nullptr;
    Json json = Json::object();
    json["file"] = summary->file;
    json["columns"] = Json::array({"k", "l", "u", "v", "lit_fraction", "residual_u", "residual_v"});
    json["lenses"] = summary->lenses;
    json["lit_lenses"] = summary->lit_lenses;
    Json integration = Json::object();
    integration["azimuths"] = summary->options.azimuths;
    integration["tolerance_px"] = number(summary->options.tolerance_px);
    integration["aperture_points"] = summary->options.aperture_points;
    json["integration"] = integration;
    const LatticeFit& fit = summary->fit;
    if (fit.valid) {
        Json f = Json::object();
        f["origin_px"] = numbers(fit.origin_px, 2);
        f["basis_px"] = Json::array({numbers(fit.basis_a_px, 2), numbers(fit.basis_b_px, 2)});
        f["lenses"] = fit.lenses;
        f["rms_residual_px"] = number(fit.rms_residual_px);
        f["max_residual_px"] = number(fit.max_residual_px);
        f["max_residual_lens"] = Json::array({fit.worst.k, fit.worst.l});
        json["lattice_fit"] = f;
    } else {
        json["lattice_fit"] = nullptr;
    }
    Json from = Json::object();
    from["rms_px"] = number(summary->from_lattice_rms_px);
    from["max_px"] = number(summary->from_lattice_max_px);
    json["from_microimage_lattice"] = from;
    return json;
}

// sensor.read_out: the chain from the noise-free picture to the raw (sensor/sensor_chain.h),
// every parameter as used, or null without one.
Json diffraction_json(const Diffraction& d, const DiffractionParams& params, const PlenopticCamera& m)
{
    if (!d.applied)
        return Json(nullptr);
    Json json = Json::object();
    json["model"] = "airy";
    json["aperture"] = d.aperture;
    json["aperture_diameter_mm"] = number(d.aperture_diameter_mm);
    json["distance_mm"] = number(d.distance_mm);
    json["wavelengths_nm"] = numbers(params.wavelengths_nm, 3);
    double radius_um[3], radius_px[3], main_um[3];
    for (int c = 0; c < 3; ++c) {
        radius_um[c] = d.airy_radius_mm[c] * 1000;
        radius_px[c] = d.airy_radius_mm[c] / m.sensor.pixel_size_mm[0];  // in pixel widths
        main_um[c] = d.main_lens_airy_radius_at_array_mm[c] * 1000;
    }
    json["airy_radius_um"] = numbers(radius_um, 3);
    json["airy_radius_px"] = numbers(radius_px, 3);
    json["kernel_radius_airy_radii"] = number(kAiryKernelRadii);
    json["main_lens_airy_radius_at_array_um"] = main_um[0] > 0 ? numbers(main_um, 3) : Json(nullptr);
    return json;
}

Json read_out_json(const SensorChainParams& c, const std::string& raw_file)
{
    if (!c.given)
        return Json(nullptr);
    Json out = Json::object();
    out["raw_file"] = raw_file.empty() ? Json(nullptr) : Json(raw_file);
    out["bayer"] = c.bayer == BayerPattern::None ? Json(nullptr) : Json(bayer_name(c.bayer));
    out["bit_depth"] = c.bit_depth;
    out["full_well_e"] = number(c.full_well_e);
    out["exposure_e"] = number(exposure_electrons(c));
    out["read_noise_e"] = number(c.read_noise_e);
    out["dark_current_e_per_s"] = number(c.dark_current_e_per_s);
    out["exposure_time_s"] = number(c.exposure_time_s);
    out["prnu"] = number(c.prnu);
    out["dsnu_e"] = number(c.dsnu_e);
    out["black_level_dn"] = c.black_level_dn;
    out["seed"] = c.seed;
    const double maximum_dn = std::ldexp(1.0, c.bit_depth) - 1;
    out["gain_dn_per_e"] = number((maximum_dn - c.black_level_dn) / c.full_well_e);
    out["chain"] = "signal = Poisson(exposure_e * value + dark_current_e_per_s * exposure_time_s); "
                   "e = min(signal * (1 + prnu * g) + dsnu_e * h + read_noise_e * n, full_well_e), g and h fixed per "
                   "site for the seed, n new per frame, all N(0, 1); DN = clamp(black_level_dn + round(e * "
                   "gain_dn_per_e), 0, 2^bit_depth - 1)";
    return out;
}

} // namespace

std::string metadata_json(const PlenopticCamera& m, const CameraParams& params, const CameraFrame& frame,
                          const SidecarFiles& files)
{
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    Json json = Json::object();
    json["format"] = "povray-plenoptic-metadata";
    json["version"] = 1;
    json["image"] = Json::object();
    json["image"]["width"] = W;
    json["image"]["height"] = H;
    json["mm_per_unit"] = number(m.mm_per_unit);

    Json camera_frame = Json::object();
    camera_frame["location"] = numbers(frame.location, 3);
    camera_frame["right"] = numbers(frame.right, 3);
    camera_frame["up"] = numbers(frame.up, 3);
    camera_frame["direction"] = numbers(frame.direction, 3);
    json["camera_frame"] = camera_frame;

    json["main_lens"] = main_lens(m);
    json["microlens_array"] = microlens_array(m, params);

    Json sensor = Json::object();
    sensor["pixel_size_mm"] = numbers(m.sensor.pixel_size_mm, 2);
    sensor["offset_mm"] = numbers(m.sensor.offset_mm, 2);
    sensor["plane_z_mm"] = number(m.sensor.z_mm);
    Json radiometry = Json::object();
    radiometry["model"] = radiometry_name(m.sensor.radiometry);
    const double solid_angle = reference_projected_solid_angle_sr(m);
    radiometry["projected_solid_angle_sr"] = number_or_null(solid_angle > 0, solid_angle);
    radiometry["angular_response"] = number(m.sensor.angular_exponent);
    sensor["radiometry"] = radiometry;
    sensor["read_out"] = read_out_json(params.sensor.chain, files.raw);
    json["sensor"] = sensor;

    Json samples = Json::object();
    samples["adaptive"] = m.sampling.adaptive;
    samples["min"] = m.sampling.samples_min;
    samples["max"] = m.sampling.samples_max;
    samples["confidence"] = number(m.sampling.confidence);
    samples["variance"] = number(m.sampling.variance);
    json["samples"] = samples;
    json["diffraction"] = diffraction_json(diffraction_of(m, params.diffraction), params.diffraction, m);

    const Vec2 principal = m.sensor.principal_point_px();
    const double principal_px[2] = {principal.x, principal.y};
    json["principal_point_px"] = numbers(principal_px, 2);

    const MicroimageLattice lattice = microimage_lattice(m);
    json["microimage_lattice"] = lattice_json(m, lattice);
    json["lftoolbox_lenslet_grid_model"] = lftoolbox(lattice);
    json["depth_map"] = files.depth_map.empty() ? Json(nullptr) : Json(files.depth_map);
    json["virtual_depth_map"] = files.virtual_depth_map.empty() ? Json(nullptr) : Json(files.virtual_depth_map);
    json["microimages"] = microimages_json(files.microimages);
    if (files.white_images == nullptr) {
        json["white_images"] = nullptr;
    } else {
        Json list = Json::array();
        for (const WhiteImageFile& w : *files.white_images) {
            Json entry = Json::object();
            entry["file"] = w.file;
            entry["f_number"] = w.f_number > 0 ? number(w.f_number) : Json(nullptr);
            entry["values"] = w.raw ? "dn" : "linear";
            entry["scale"] = number(w.scale);
            list.push_back(entry);
        }
        json["white_images"] = list;
    }

    std::string text;
    layout(json, 0, false, &text);
    return text + "\n";
}

} // namespace plenoptic
