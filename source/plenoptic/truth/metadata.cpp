// SPDX-License-Identifier: AGPL-3.0-or-later
// Writes the plenoptic render metadata (docs/metadata.md) with nlohmann-json: the document is
// built as an ordered_json (members in the documented order) from the sections the camera's parts
// write (the main lens, the sensor, the sampling) and the camera-level ones written here; every
// number and string is serialised by the library; only the line layout is chosen here.

#include "plenoptic/truth/metadata.h"

#include <algorithm>
#include <cmath>

#include "plenoptic/core/json.h"
#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/truth/distortion_profile.h"
#include "plenoptic/optics.h"
#include "plenoptic/camera/radiometry.h"

namespace plenoptic {

namespace {

using Json = MetadataJson;


// Field heights of the distortion profile, 0 to the picture's corner in sixteenths.
const int kDistortionProfileSamples = 17;

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

Json profile_rows(const DistortionProfile& profile)
{
    Json samples = Json::array();
    for (const DistortionSample& s : profile.samples) {
        const double percent = s.paraxial_height_mm > 0 ? 100 * (s.real_height_mm / s.paraxial_height_mm - 1) : NAN;
        samples.push_back(Json::array({json_number(s.relative_field), json_number(s.field_angle_deg), json_number(s.paraxial_height_mm),
                                       json_number(s.real_height_mm), json_number(percent)}));
    }
    return samples;
}

// A dispersing lens's profile per colour channel: the same object points' chief rays traced at
// each channel's wavelength (channel_wavelengths_nm), against the d line's paraxial heights; null
// rows for a channel whose profile does not exist.
Json channel_profiles_json(const PlenopticCamera& m, const CameraParams& params)
{
    double nm[3];
    channel_wavelengths_nm(params.spectral, nm);
    const char* names[3] = {"r", "g", "b"};
    Json json = Json::object();
    json["wavelengths_nm"] = json_numbers(nm, 3);
    for (int c = 0; c < 3; ++c) {
        const PlenopticCamera at = at_wavelength(m, nm[c]);
        const DistortionProfile profile = distortion_profile(m, kDistortionProfileSamples, &at);
        json[names[c]] = profile.valid ? profile_rows(profile) : Json(nullptr);
    }
    return json;
}

// The chief ray's image height over the field against the paraxial one (null when the lens has
// no profile); a dispersing lens's adds "channels".
Json distortion_profile_json(const PlenopticCamera& m, const CameraParams& params)
{
    const DistortionProfile profile = distortion_profile(m, kDistortionProfileSamples);
    if (!profile.valid)
        return nullptr;
    Json json = Json::object();
    json["object_plane_z_mm"] = profile.object_at_infinity ? Json(nullptr) : json_number(profile.object_plane_z_mm);
    json["image_plane_z_mm"] = json_number(profile.image_plane_z_mm);
    json["chief_ray"] = m.lens->chief_ray_description();
    json["columns"] = Json::array({"relative_field", "field_angle_deg", "paraxial_height_mm", "real_height_mm", "distortion_percent"});
    json["samples"] = profile_rows(profile);
    if (m.lens->prescription() && dispersive(*m.lens->prescription()))
        json["channels"] = channel_profiles_json(m, params);
    return json;
}

// The main lens's section as the lens writes it, held where this camera holds it, and the
// distortion profile measured through the camera.
Json main_lens(const PlenopticCamera& m, const CameraParams& params)
{
    Json json = main_lens_metadata(m.lens.get(), LensPlacement{m.distance_mm, m.has_focus_distance,
                                                               m.focus_distance_units, m.lens_file()});
    json["distortion_profile"] = distortion_profile_json(m, params);
    return json;
}

Json lattice_json(const PlenopticCamera& m, const MicroimageLattice& lattice)
{
    if (!lattice.valid)
        return nullptr;
    const bool hexagonal = m.array.grid == GridType::Hexagonal;
    Json json = Json::object();
    json["origin_px"] = json_numbers(lattice.origin_px, 2);
    json["basis_px"] = Json::array({json_numbers(lattice.basis_a_px, 2), json_numbers(lattice.basis_b_px, 2)});
    json["index_rule"] = hexagonal
                             ? "skew indices (k, l): hexagonal centres in the array are k*(p,0) + l*(p/2, p*sqrt(3)/2)"
                             : "skew indices (k, l): rectangular centres in the array are k*(p,0) + l*(0,p)";
    json["exact"] = lattice.exact;
    const int types = m.array.lens_type_count;
    json["lens_types"] = types;
    json["lens_type_rule"] = types == 3 ? "type(k, l) = (k - l) mod 3, focal_lengths_mm[type]" : "type(k, l) = 0";
    // Diameter of the main lens's exit pupil imaged through a lens centre (the f-number-matched disc).
    const bool has_pupil = m.lens && m.lens->forms_image();
    const double pupil_mm = has_pupil ? 2 * m.lens->exit_pupil_radius() : 0;  // a thin lens's: A (2 * A/2, exact)
    json["microimage_diameter_px"] =
        json_number_or_null(has_pupil, pupil_mm * effective_array_distance_mm(m) / effective_main_distance_mm(m) / m.sensor.pixel_size_mm[0]);
    return json;
}

Json lftoolbox(const MicroimageLattice& lattice)
{
    if (!lattice.valid || !lattice.lftoolbox_valid)
        return nullptr;
    Json json = Json::object();
    json["HSpacing"] = json_number(lattice.h_spacing);
    json["VSpacing"] = json_number(lattice.v_spacing);
    json["HOffset"] = json_number(lattice.h_offset);
    json["VOffset"] = json_number(lattice.v_offset);
    json["Rot"] = json_number(lattice.rot);
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
    if (summary->per_channel) {
        for (const char* column : {"u_r", "v_r", "u_g", "v_g", "u_b", "v_b"})
            json["columns"].push_back(column);
        json["channel_wavelengths_nm"] = json_numbers(summary->channel_wavelengths_nm, 3);
    }
    if (summary->lens_errors)
        for (const char* column : {"dx_mm", "dy_mm", "dz_mm", "focal_length_mm", "tilt_deg", "tilt_azimuth_deg"})
            json["columns"].push_back(column);
    json["lenses"] = summary->lenses;
    json["lit_lenses"] = summary->lit_lenses;
    Json integration = Json::object();
    integration["azimuths"] = summary->options.azimuths;
    integration["tolerance_px"] = json_number(summary->options.tolerance_px);
    integration["aperture_points"] = summary->options.aperture_points;
    if (summary->work.anchors > 0) {
        // Refracting microlenses between anchors (docs/real-lenses.md, "Microimage centres").
        integration["anchor_step"] = summary->options.anchor_step;
        integration["anchors"] = summary->work.anchors;
        integration["interpolated_lenses"] = summary->work.interpolated;
    }
    if (summary->work.quarter_lenses > 0)
        integration["quarter_lenses"] = summary->work.quarter_lenses;  // measured; the others mirror them
    if (summary->work.corrected > 0) {
        // Refracting microlenses with errors, corrected (docs/real-lenses.md, "Microimage centres").
        integration["error_anchor_step"] = summary->options.error_anchor_step;
        integration["error_anchors"] = summary->work.error_anchors;
        integration["corrected_lenses"] = summary->work.corrected;
    }
    json["integration"] = integration;
    const LatticeFit& fit = summary->fit;
    if (fit.valid) {
        Json f = Json::object();
        f["origin_px"] = json_numbers(fit.origin_px, 2);
        f["basis_px"] = Json::array({json_numbers(fit.basis_a_px, 2), json_numbers(fit.basis_b_px, 2)});
        f["lenses"] = fit.lenses;
        f["rms_residual_px"] = json_number(fit.rms_residual_px);
        f["max_residual_px"] = json_number(fit.max_residual_px);
        f["max_residual_lens"] = Json::array({fit.worst.k, fit.worst.l});
        json["lattice_fit"] = f;
    } else {
        json["lattice_fit"] = nullptr;
    }
    Json from = Json::object();
    from["rms_px"] = json_number(summary->from_lattice_rms_px);
    from["max_px"] = json_number(summary->from_lattice_max_px);
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
    json["aperture_diameter_mm"] = json_number(d.aperture_diameter_mm);
    json["distance_mm"] = json_number(d.distance_mm);
    json["wavelengths_nm"] = json_numbers(params.wavelengths_nm, 3);
    double radius_um[3], radius_px[3], main_um[3];
    for (int c = 0; c < 3; ++c) {
        radius_um[c] = d.airy_radius_mm[c] * 1000;
        radius_px[c] = d.airy_radius_mm[c] / m.sensor.pixel_size_mm[0];  // in pixel widths
        main_um[c] = d.main_lens_airy_radius_at_array_mm[c] * 1000;
    }
    json["airy_radius_um"] = json_numbers(radius_um, 3);
    json["airy_radius_px"] = json_numbers(radius_px, 3);
    json["kernel_radius_airy_radii"] = json_number(kAiryKernelRadii);
    json["main_lens_airy_radius_at_array_um"] = main_um[0] > 0 ? json_numbers(main_um, 3) : Json(nullptr);
    return json;
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
    json["mm_per_unit"] = json_number(m.mm_per_unit);

    Json camera_frame = Json::object();
    camera_frame["location"] = json_numbers(frame.location);
    camera_frame["right"] = json_numbers(frame.right);
    camera_frame["up"] = json_numbers(frame.up);
    camera_frame["direction"] = json_numbers(frame.direction);
    json["camera_frame"] = camera_frame;

    json["main_lens"] = main_lens(m, params);
    json["microlens_array"] =
        m.array.present() ? m.array.metadata(params.array.rotate_deg, params.array.translate_mm) : Json(nullptr);

    json["sensor"] = m.sensor.metadata(reference_projected_solid_angle_sr(m), params.sensor.chain, files.raw);
    json["samples"] = m.sampling.metadata();
    if (params.spectral.given())
        json["spectral"] = spectral_metadata(params.spectral);  // only with `spectral`
    json["diffraction"] = diffraction_json(diffraction_of(m, params.diffraction), params.diffraction, m);

    const Vec2 principal = m.sensor.principal_point_px();
    const double principal_px[2] = {principal.x, principal.y};
    json["principal_point_px"] = json_numbers(principal_px, 2);

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
            entry["f_number"] = w.f_number > 0 ? json_number(w.f_number) : Json(nullptr);
            entry["values"] = w.raw ? "dn" : "linear";
            entry["scale"] = json_number(w.scale);
            list.push_back(entry);
        }
        json["white_images"] = list;
    }

    std::string text;
    layout(json, 0, false, &text);
    return text + "\n";
}

} // namespace plenoptic
