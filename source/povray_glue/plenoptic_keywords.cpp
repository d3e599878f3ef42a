// SPDX-License-Identifier: AGPL-3.0-or-later
// The plenoptic camera's keyword table (plenoptic_keywords.h). The checks and the numeric defaults
// live with the parameters (camera/params.h, sensor/sensor_chain.h, sensor/diffraction.h); a row
// names the check and states the default as docs/specification.md does.

#include "povray_glue/plenoptic_keywords.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "plenoptic/camera/radiometry.h"
#include "plenoptic/lens/glass.h"
#include "plenoptic/sensor/diffraction.h"
#include "plenoptic/sensor/sensor_chain.h"

namespace plenoptic {

namespace {

typedef KeywordBlock B;
typedef KeywordValue V;
typedef KeywordGroup G;
typedef const KeywordRead& R;

// Checks whose functions take no keyword.
std::string Check_F_Number(const char *, double value) { return check_f_number(value); }
std::string Check_Focus_Distance(const char *, double value) { return check_focus_distance(value); }
std::string Check_Mm_Per_Unit(const char *, double value) { return check_mm_per_unit(value); }
std::string Check_Confidence(const char *, double value) { return check_confidence(value); }
// 0 (every lens measured) or a spacing of at least 4 lenses (MicroimageOptions::error_anchor_step).
std::string Check_Error_Anchors(const char *label, double value)
{
    if (!(value == 0 || (value >= 4 && value <= 4096 && value == std::floor(value))))
        return std::string(label) + " must be 0 (every lens measured) or a whole number of lenses from 4 to 4096, got " +
               format_number(value);
    return "";
}
std::string Check_Variance(const char *, double value) { return check_variance(value); }
std::string Check_Blades(const char *, double value) { return check_blades(value); }
std::string Check_Wavelength(const char *, double value) { return check_wavelength(value); }
std::string Check_Angular_Exponent(const char *, double value) { return check_angular_exponent(value); }
std::string Check_Spectral_Bands(const char *, double value) { return check_spectral_bands(value); }
std::string Check_Response_Centre(const char *label, double value)
{
    if (!(value >= kMinWavelengthNm && value <= kMaxWavelengthNm))
        return std::string(label) + " are in nanometres, from " + format_number(kMinWavelengthNm) + " to " +
               format_number(kMaxWavelengthNm) + ", got " + format_number(value);
    return "";
}
std::string Check_Response_Width(const char *label, double value)
{
    if (!(value >= kMinResponseWidthNm && value <= kMaxResponseWidthNm))
        return std::string(label) + " are full widths at half maximum in nanometres, from " +
               format_number(kMinResponseWidthNm) + " to " + format_number(kMaxResponseWidthNm) + ", got " +
               format_number(value);
    return "";
}
std::string Check_Abbe(const char *label, double value)
{
    const std::string message = check_abbe(value);
    return message.empty() ? message : std::string(label) + ": " + message;
}
std::string Check_Fill_Factor(const char *, double value) { return check_fill_factor(value); }
std::string Check_Error_Deviation(const char *label, double value) { return check_error_deviation(label, value); }
std::string Check_Error_Rotation(const char *, double value) { return check_error_rotation(value); }
std::string Check_White_F_Number(const char *, double value)
{
    const std::string message = check_f_number(value);
    return message.empty() ? message : "white_image f_numbers: " + message;
}

const BayerPattern kBayerPatterns[] = {BayerPattern::RGGB, BayerPattern::BGGR, BayerPattern::GRBG, BayerPattern::GBRG};
const char *Bayer_Word(int index) { return (index >= 0 && index < 4) ? bayer_name(kBayerPatterns[index]) : nullptr; }
const char *Curved_Side_Word(int index) { return index == 0 ? "scene" : index == 1 ? "sensor" : nullptr; }
std::string Check_Microlens_Ior(const char *label, double value) { return check_microlens_ior(label, value); }
std::string Check_Microlens_Conic(const char *label, double value) { return check_microlens_conic(label, value); }
const Radiometry kRadiometries[] = {Radiometry::Flat, Radiometry::Irradiance};
const char *Radiometry_Word(int index) { return (index >= 0 && index < 2) ? radiometry_name(kRadiometries[index]) : nullptr; }

MainLensParams& lens(CameraSetup& s) { return s.params.main; }
ArrayParams& array(CameraSetup& s) { return s.params.array; }
SensorChainParams& chain(CameraSetup& s) { return s.params.sensor.chain; }
LensSurface& row(CameraSetup& s) { return s.params.main.prescription.surfaces.back(); }
void set_microlens(CameraSetup& s, MicrolensType type, int focal_lengths)
{
    array(s).lens = type;
    array(s).focal_length_count = focal_lengths;
    array(s).has_lens = true;
}

std::vector<Keyword> make_table()
{
    return {
        // ---- camera { plenoptic ... } ----
        Keyword("main_lens", B::Camera, V::Block, "none: no main lens", "the main lens",
                [](CameraSetup& s, R) { lens(s) = MainLensParams(); lens(s).given = true; })
            .opening(B::MainLens).listed_as("main_lens { }"),
        Keyword("microlens_array", B::Camera, V::Block, "none: no array", "the microlens array in front of the sensor",
                [](CameraSetup& s, R) { array(s) = ArrayParams(); array(s).given = true; })
            .opening(B::MicrolensArray).listed_as("microlens_array { }"),
        // A second sensor { } replaces the first entirely, as the other blocks do.
        Keyword("sensor", B::Camera, V::Block, "10 µm square pixels, centred on the axis, no read-out",
                "the sensor: pixel size and offset, angular response, read-out to a raw",
                [](CameraSetup& s, R) { s.params.sensor = SensorParams(); })
            .opening(B::Sensor).listed_as("sensor { }"),
        Keyword("mm_per_unit", B::Camera, V::Number, "1000", "millimetres per scene unit",
                [](CameraSetup& s, R r) { s.params.mm_per_unit = r.values[0]; })
            .reserved_word().checked(Check_Mm_Per_Unit),
        Keyword("samples", B::Camera, V::Samples, "16 when an aperture is sampled, else 1",
                "rays per pixel: N, or MIN, MAX for adaptive sampling",
                [](CameraSetup& s, R r) {
                    // values[1] is 0 for a fixed count N (values[0]); else MIN, MAX.
                    SamplingParams& sampling = s.params.sampling;
                    sampling.adaptive = (r.values[1] != 0.0);
                    if (sampling.adaptive)
                    {
                        sampling.samples_min = (int)r.values[0];
                        sampling.samples_max = (int)r.values[1];
                    }
                    sampling.samples = (int)(sampling.adaptive ? r.values[1] : r.values[0]);
                })
            .reserved_word().checked(check_samples),
        Keyword("confidence", B::Camera, V::Number, "0.9", "adaptive sampling: the confidence of the stopping test",
                [](CameraSetup& s, R r) { s.params.sampling.confidence = r.values[0]; })
            .reserved_word().checked(Check_Confidence),
        Keyword("variance", B::Camera, V::Number, "1/128", "adaptive sampling: the variance below which a pixel stops",
                [](CameraSetup& s, R r) { s.params.sampling.variance = r.values[0]; })
            .reserved_word().checked(Check_Variance),
        Keyword("depth_map", B::Camera, V::OnOff, "off", "also write the depth map (and the virtual depth map)",
                [](CameraSetup& s, R r) { s.depth_map = (r.values[0] != 0); }),
        Keyword("microimage_centres", B::Camera, V::OnOff,
                "on behind a traced real lens or a thin lens with distortion, off otherwise",
                "also write the microimage centres of a white scene",
                [](CameraSetup& s, R r) {
                    s.microimage_centres = (r.values[0] != 0) ? CameraSetup::kWrite : CameraSetup::kDoNotWrite;
                }),
        Keyword("microimage_error_anchors", B::Camera, V::Number, "0",
                "refracting microlenses with manufacturing errors: the microimage centres correct each lens from "
                "Jacobian anchors N lenses apart (0: every lens measured)",
                [](CameraSetup& s, R r) { s.microimage_error_anchors = (int)r.values[0]; })
            .checked(Check_Error_Anchors),
        Keyword("white_image", B::Camera, V::OnOff, "off", "also write the camera's white image(s)",
                [](CameraSetup& s, R r) {
                    s.white_image = WhiteImageRequest();
                    s.white_f_numbers = CameraSetup::KeywordSource();
                    s.white_image.given = (r.values[0] != 0);
                })
            .opening(B::WhiteImage),
        Keyword("radiometry", B::Camera, V::Word, "flat", "what a pixel's value measures: flat or irradiance",
                [](CameraSetup& s, R r) { s.params.radiometry = kRadiometries[(int)r.values[0]]; })
            .words(Radiometry_Word),
        Keyword("diffraction", B::Camera, V::OnOff, "off", "convolve the picture with the Airy pattern, one wavelength per channel",
                [](CameraSetup& s, R r) {
                    s.params.diffraction = DiffractionParams();
                    s.params.diffraction.given = (r.values[0] != 0);
                })
            .opening(B::Diffraction),

        Keyword("spectral", B::Camera, V::Number, "off",
                "trace each sample at one of N wavelength bands (380 to 720 nm), weighed by the sensor's response",
                [](CameraSetup& s, R r) {
                    s.params.spectral = SpectralParams();
                    s.params.spectral.bands = (int)r.values[0];
                })
            .checked(Check_Spectral_Bands).opening(B::Spectral),

        // ---- white_image's modifiers ----
        Keyword("f_numbers", B::WhiteImage, V::FNumbers, "the camera's own aperture: one file, <image stem>.white.png",
                "one white image per f-number, the main lens set to it",
                [](CameraSetup& s, R r) {
                    s.white_image.f_numbers = r.list;
                    s.white_f_numbers.keyword = "f_numbers";
                    s.white_f_numbers.line = r.line;
                    s.white_f_numbers.column = r.column;
                    s.white_f_numbers.offset = r.offset;
                })
            .labelled("white_image f_numbers").checked(Check_White_F_Number),
        Keyword("noise_free", B::WhiteImage, V::Flag, "off", "write the linear white image even with a sensor read-out",
                [](CameraSetup& s, R) { s.white_image.noise_free = true; }),

        // ---- diffraction's modifiers ----
        Keyword("wavelengths", B::Diffraction, V::Vector3, "<610, 550, 465>", "the wavelength of each colour channel (nm)",
                [](CameraSetup& s, R r) { std::copy(r.values, r.values + 3, s.params.diffraction.wavelengths_nm); })
            .labelled("diffraction wavelengths").checked(Check_Wavelength),

        // ---- spectral's modifiers ----
        Keyword("response_centres", B::Spectral, V::Vector3, "<610, 550, 465>",
                "the centres of the sensor's Gaussian sensitivities, R, G, B (nm)",
                [](CameraSetup& s, R r) {
                    std::copy(r.values, r.values + 3, s.params.spectral.response.centre_nm);
                    s.params.spectral.gaussian_written = true;
                })
            .labelled("spectral response_centres").checked(Check_Response_Centre),
        Keyword("response_widths", B::Spectral, V::Vector3, "<90, 90, 90>",
                "their full widths at half maximum, R, G, B (nm)",
                [](CameraSetup& s, R r) {
                    std::copy(r.values, r.values + 3, s.params.spectral.response.fwhm_nm);
                    s.params.spectral.gaussian_written = true;
                })
            .labelled("spectral response_widths").checked(Check_Response_Width),
        Keyword("response_file", B::Spectral, V::ResponseFile, "Gaussian sensitivities",
                "the sensor's sensitivities tabulated: wavelength_nm, r, g, b per row",
                [](CameraSetup& s, R r) { s.params.spectral.response = r.response; }),

        // ---- main_lens { } ----
        Keyword("thin_lens", B::MainLens, V::Flag, "", "an ideal thin lens",
                [](CameraSetup& s, R) { lens(s).type = MainLensType::ThinLens; })
            .in_group(G::MainLensKind),
        Keyword("pinhole", B::MainLens, V::Flag, "", "a pinhole",
                [](CameraSetup& s, R) { lens(s).type = MainLensType::Pinhole; })
            .in_group(G::MainLensKind),
        Keyword("thick_lens", B::MainLens, V::Flag, "", "the real lens's paraxial equivalent instead of its trace",
                [](CameraSetup& s, R) { lens(s).type = MainLensType::ThickLens; })
            .in_group(G::MainLensKind),
        Keyword("lens_file", B::MainLens, V::String, "", "a real lens whose rows are read from a lens file",
                [](CameraSetup& s, R r) {
                    lens(s).prescription.surfaces = r.prescription.surfaces;
                    lens(s).lens_file = r.text;
                    lens(s).has_prescription = true;
                })
            .in_group(G::LensSource),
        Keyword("prescription", B::MainLens, V::Block, "", "a real lens whose rows are written in the scene",
                [](CameraSetup& s, R) {
                    lens(s).prescription.surfaces.clear();
                    lens(s).lens_file.clear();
                    lens(s).has_prescription = true;
                })
            .in_group(G::LensSource).opening(B::Prescription).listed_as("prescription { }"),
        Keyword("focal_length", B::MainLens, V::Number, "", "the thin lens's focal length (mm)",
                [](CameraSetup& s, R r) { lens(s).focal_length_mm = r.values[0]; lens(s).has_focal_length = true; })
            .labelled("main_lens focal_length").checked(check_positive_length),
        Keyword("f_number", B::MainLens, V::Number, "thin lens: none; real lens: the stop as written", "the lens's f-number",
                [](CameraSetup& s, R r) { lens(s).f_number = r.values[0]; lens(s).has_f_number = true; })
            .checked(Check_F_Number),
        Keyword("aperture", B::MainLens, V::Number, "as f_number", "the aperture's (a real lens's stop's) diameter (mm)",
                [](CameraSetup& s, R r) { lens(s).aperture_mm = r.values[0]; lens(s).has_aperture = true; })
            .reserved_word().checked(check_positive_length),
        Keyword("focus_distance", B::MainLens, V::Number, "", "the plane in focus, in scene units in front of the lens",
                [](CameraSetup& s, R r) { lens(s).focus_distance_units = r.values[0]; lens(s).has_focus_distance = true; })
            .checked(Check_Focus_Distance),
        Keyword("distance", B::MainLens, V::Number, "", "D: main lens to array, or to sensor without one (mm)",
                [](CameraSetup& s, R r) { lens(s).distance_mm = r.values[0]; lens(s).has_distance = true; })
            .reserved_word().labelled("main_lens distance").checked(check_positive_length),
        Keyword("blades", B::MainLens, V::Number, "none: a round stop", "a polygonal iris of N blades",
                [](CameraSetup& s, R r) { lens(s).blades = (int)r.values[0]; })
            .checked(Check_Blades),
        Keyword("blade_rotation", B::MainLens, V::Number, "0", "turns the iris (degrees)",
                [](CameraSetup& s, R r) { lens(s).blade_rotation_deg = r.values[0]; })
            .checked(check_angle),
        Keyword("distortion", B::MainLens, V::Block, "none", "Brown-Conrady distortion of the thin lens",
                [](CameraSetup& s, R) { lens(s).has_distortion = true; })
            .in_group(G::Distortion).opening(B::Distortion).listed_as("distortion { }"),

        // ---- distortion { } ----
        Keyword("radial", B::Distortion, V::Vector3, "<0, 0, 0>", "the radial coefficients k1, k2, k3",
                [](CameraSetup& s, R r) { std::copy(r.values, r.values + 3, lens(s).distortion.radial); })
            .reserved_word().labelled("distortion radial").listed_as("radial <k1, k2, k3>"),
        Keyword("tangential", B::Distortion, V::Vector2, "<0, 0>", "the tangential coefficients p1, p2",
                [](CameraSetup& s, R r) { std::copy(r.values, r.values + 2, lens(s).distortion.tangential); })
            .labelled("distortion tangential").listed_as("tangential <p1, p2>"),

        // ---- prescription { }: rows object side first. A stop keeps the medium it stands in
        // (index 0, as in a lens file); a radius 0 surface is flat. ----
        Keyword("surface", B::Prescription, V::Block, "", "a spherical refracting surface",
                [](CameraSetup& s, R r) {
                    lens(s).prescription.surfaces.push_back(LensSurface{0, 0, 1.0, 0, false, (int)r.line});
                })
            .opening(B::Surface).listed_as("surface { }"),
        Keyword("stop", B::Prescription, V::Block, "", "the aperture stop",
                [](CameraSetup& s, R r) {
                    lens(s).prescription.surfaces.push_back(LensSurface{0, 0, 0.0, 0, true, (int)r.line});
                })
            .opening(B::Stop).listed_as("stop { }"),

        // ---- surface { } ----
        // Beyond +-1e12 mm (the bound of every length) a radius is flat, as in a lens file.
        Keyword("radius", B::Surface, V::Number, "", "the radius of curvature (mm)",
                [](CameraSetup& s, R r) { row(s).radius_mm = flat_radius(r.values[0]); })
            .reserved_word().labelled("surface radius").needed_in_block(),
        Keyword("thickness", B::Surface, V::Number, "", "the axial distance to the next row (mm)",
                [](CameraSetup& s, R r) { row(s).thickness_mm = r.values[0]; })
            .reserved_word().labelled("surface thickness").checked(check_translation).needed_in_block(),
        Keyword("ior", B::Surface, V::Number, "", "the index of refraction after the surface",
                [](CameraSetup& s, R r) { row(s).ior = r.values[0]; })
            .reserved_word().labelled("surface ior").needed_in_block(),
        Keyword("aperture", B::Surface, V::Number, "", "the clear aperture's diameter (mm)",
                [](CameraSetup& s, R r) { row(s).aperture_mm = r.values[0]; })
            .reserved_word().labelled("surface aperture").checked(check_positive_length).needed_in_block(),
        // The medium's dispersion (lens/glass.h); checked with the whole glass at prescription's }.
        Keyword("abbe", B::Surface, V::Number, "0: no dispersion", "the Abbe number V_d of the medium after the surface",
                [](CameraSetup& s, R r) { row(s).glass.abbe = r.values[0]; })
            .labelled("surface abbe").checked(Check_Abbe),
        Keyword("sellmeier", B::Surface, V::Vector6, "none", "the medium's Sellmeier coefficients B1, B2, B3, C1, C2, C3 (C in µm²)",
                [](CameraSetup& s, R r) {
                    row(s).glass.sellmeier = true;
                    std::copy(r.list.begin(), r.list.begin() + 3, row(s).glass.sellmeier_b);
                    std::copy(r.list.begin() + 3, r.list.begin() + 6, row(s).glass.sellmeier_c_um2);
                })
            .labelled("surface sellmeier").listed_as("sellmeier <B1, B2, B3, C1, C2, C3>"),
        // Conic and even-asphere terms (prescription.h surface_sag_mm); checked at prescription's }.
        Keyword("conic", B::Surface, V::Number, "0: a sphere", "the conic constant k of the surface (-1: a paraboloid)",
                [](CameraSetup& s, R r) { row(s).conic = r.values[0]; })
            .labelled("surface conic"),
        Keyword("aspheric", B::Surface, V::FloatList, "none", "the even-asphere terms a4, a6, ..., a18 (mm^-3, mm^-5, ...)",
                [](CameraSetup& s, R r) {
                    row(s).aspheric_count = int(r.list.size());
                    std::fill(row(s).aspheric, row(s).aspheric + LensSurface::kMaxAspheric, 0.0);
                    std::copy(r.list.begin(), r.list.end(), row(s).aspheric);
                })
            .labelled("surface aspheric").listed_as("aspheric <a4, a6, ...>"),

        // ---- stop { } ----
        Keyword("thickness", B::Stop, V::Number, "", "the axial distance to the next row (mm)",
                [](CameraSetup& s, R r) { row(s).thickness_mm = r.values[0]; })
            .reserved_word().labelled("stop thickness").checked(check_translation).needed_in_block(),
        Keyword("aperture", B::Stop, V::Number, "", "the stop's diameter as written (mm)",
                [](CameraSetup& s, R r) { row(s).aperture_mm = r.values[0]; })
            .reserved_word().labelled("stop aperture").checked(check_positive_length).needed_in_block(),

        // ---- microlens_array { } ----
        Keyword("hexagonal", B::MicrolensArray, V::Flag, "", "lens centres on a hexagonal lattice",
                [](CameraSetup& s, R) { array(s).grid = GridType::Hexagonal; })
            .in_group(G::Grid),
        Keyword("rectangular", B::MicrolensArray, V::Flag, "", "lens centres on a square lattice",
                [](CameraSetup& s, R) { array(s).grid = GridType::Rectangular; })
            .in_group(G::Grid),
        Keyword("pitch", B::MicrolensArray, V::Number, "", "the distance between neighbouring lens centres (mm)",
                [](CameraSetup& s, R r) { array(s).pitch_mm = r.values[0]; array(s).has_pitch = true; })
            .checked(check_positive_length),
        Keyword("focal_length", B::MicrolensArray, V::Number, "", "every microlens a thin lens of this focal length (mm)",
                [](CameraSetup& s, R r) {
                    array(s).focal_lengths_mm[0] = r.values[0];
                    set_microlens(s, MicrolensType::ThinLens, 1);
                })
            .labelled("microlens_array focal_length").checked(check_positive_length).in_group(G::MicrolensKind),
        Keyword("focal_lengths", B::MicrolensArray, V::Vector3, "", "three interleaved lens types (multi-focus) (mm)",
                [](CameraSetup& s, R r) {
                    std::copy(r.values, r.values + 3, array(s).focal_lengths_mm);
                    set_microlens(s, MicrolensType::ThinLens, 3);
                })
            .checked(check_positive_length).in_group(G::MicrolensKind),
        Keyword("pinhole", B::MicrolensArray, V::Flag, "", "every microlens a pinhole",
                [](CameraSetup& s, R) { set_microlens(s, MicrolensType::Pinhole, 0); })
            .in_group(G::MicrolensKind),
        Keyword("lens", B::MicrolensArray, V::Block, "", "every microlens a refracting plano-convex cap on a substrate",
                [](CameraSetup& s, R) {
                    set_microlens(s, MicrolensType::Refracting, 0);
                    array(s).refracting = RefractingShape();
                })
            .in_group(G::MicrolensKind).opening(B::Microlens).listed_as("lens { }"),
        Keyword("distance", B::MicrolensArray, V::Number, "", "d: array to sensor (mm)",
                [](CameraSetup& s, R r) { array(s).distance_mm = r.values[0]; array(s).has_distance = true; })
            .reserved_word().labelled("microlens_array distance").checked(check_positive_length),
        // The pose is one rotation then one translation (docs/specification.md, section 2): not a chain.
        Keyword("rotate", B::MicrolensArray, V::Vector3, "<0, 0, 0>", "pose error: rotation about x, then y, then z (degrees)",
                [](CameraSetup& s, R r) { std::copy(r.values, r.values + 3, array(s).rotate_deg); })
            .reserved_word().labelled("microlens_array rotate").checked(check_angle).in_group(G::ArrayRotate),
        Keyword("translate", B::MicrolensArray, V::Vector3, "<0, 0, 0>", "pose error: shift after the rotation (mm)",
                [](CameraSetup& s, R r) { std::copy(r.values, r.values + 3, array(s).translate_mm); })
            .reserved_word().labelled("microlens_array translate").checked(check_translation).in_group(G::ArrayTranslate),
        Keyword("abbe", B::MicrolensArray, V::Number, "0: no dispersion", "the microlenses' Abbe number V_d",
                [](CameraSetup& s, R r) { array(s).abbe = r.values[0]; })
            .labelled("microlens_array abbe").checked(Check_Abbe),
        Keyword("errors", B::MicrolensArray, V::Block, "none: ideal lenses", "manufacturing errors drawn lens by lens",
                [](CameraSetup& s, R) { array(s).has_errors = true; })
            .opening(B::Errors).listed_as("errors { }").in_group(G::ArrayErrors),
        Keyword("lens_table", B::MicrolensArray, V::LensTable, "none", "manufacturing errors measured lens by lens (CSV)",
                [](CameraSetup& s, R r) { array(s).lens_table_file = r.text; array(s).lens_table = r.lens_table; })
            .listed_as("lens_table \"file.csv\"").in_group(G::ArrayErrors),
        Keyword("fill_factor", B::MicrolensArray, V::Number, "1", "the part of each cell that is lens",
                [](CameraSetup& s, R r) { array(s).fill_factor = r.values[0]; })
            .labelled("microlens_array fill_factor").checked(Check_Fill_Factor),
        Keyword("mask", B::MicrolensArray, V::OnOff, "off", "the gap between lenses is opaque (a chrome mask)",
                [](CameraSetup& s, R r) { array(s).mask = r.values[0] != 0; }),
        Keyword("baffles", B::MicrolensArray, V::OnOff, "off", "walls between microimages: no light under a neighbour",
                [](CameraSetup& s, R r) { array(s).baffles = r.values[0] != 0; }),

        // ---- microlens_array { errors { } } ----
        Keyword("position", B::Errors, V::NumberPair, "0", "S [, S_z]: standard deviation of each lens's shift in the "
                "array's plane [and along its normal] (mm)",
                [](CameraSetup& s, R r) {
                    array(s).errors.position_sd_mm = r.values[0];
                    array(s).errors.position_sd_z_mm = r.values[1];
                })
            .labelled("errors position").checked(Check_Error_Deviation),
        Keyword("focal_length", B::Errors, V::Number, "0", "relative standard deviation of the focal lengths",
                [](CameraSetup& s, R r) { array(s).errors.focal_sd = r.values[0]; })
            .labelled("errors focal_length").checked(Check_Error_Deviation),
        Keyword("rotation", B::Errors, V::Number, "0", "the largest tilt of a lens's axis (degrees)",
                [](CameraSetup& s, R r) { array(s).errors.rotation_deg = r.values[0]; })
            .labelled("errors rotation").checked(Check_Error_Rotation),
        Keyword("seed", B::Errors, V::Number, "0", "which array of the distribution",
                [](CameraSetup& s, R r) { array(s).errors.seed = (std::int64_t)r.values[0]; })
            .reserved_word().labelled("errors seed").checked(check_whole_number),

        // ---- microlens_array { lens { } }: refracting microlenses (array/refracting_microlens.h) ----
        Keyword("surface", B::Microlens, V::Block, "", "the cap's curved surface",
                [](CameraSetup& s, R) {
                    array(s).refracting.radius_mm = 0;
                    array(s).refracting.conic = 0;
                })
            .in_group(G::MicrolensSurface).needed_in_block().opening(B::MicrolensSurface).listed_as("surface { }"),
        Keyword("thickness", B::Microlens, V::Number, "", "t: the cap's centre thickness (mm)",
                [](CameraSetup& s, R r) { array(s).refracting.cap_mm = r.values[0]; })
            .reserved_word().labelled("microlens_array lens thickness").checked(check_positive_length).needed_in_block(),
        Keyword("ior", B::Microlens, V::Number, "", "n: the index of refraction of the cap and substrate",
                [](CameraSetup& s, R r) { array(s).refracting.ior = r.values[0]; })
            .reserved_word().labelled("microlens_array lens ior").checked(Check_Microlens_Ior).needed_in_block(),
        Keyword("substrate", B::Microlens, V::Number, "", "T: the substrate's thickness below the caps (mm)",
                [](CameraSetup& s, R r) { array(s).refracting.substrate_mm = r.values[0]; })
            .labelled("microlens_array lens substrate").checked(check_positive_length).needed_in_block(),
        Keyword("curved_side", B::Microlens, V::Word, "scene", "which side the caps face: scene or sensor",
                [](CameraSetup& s, R r) { array(s).refracting.curved_towards_scene = (int)r.values[0] == 0; })
            .words(Curved_Side_Word).listed_as("curved_side scene|sensor"),

        // ---- microlens_array { lens { surface { } } } ----
        Keyword("radius", B::MicrolensSurface, V::Number, "", "R: the cap's radius of curvature at its vertex (mm)",
                [](CameraSetup& s, R r) { array(s).refracting.radius_mm = r.values[0]; })
            .reserved_word().labelled("microlens_array lens surface radius").checked(check_positive_length).needed_in_block(),
        Keyword("conic", B::MicrolensSurface, V::Number, "0: a sphere", "k: the cap's conic constant",
                [](CameraSetup& s, R r) { array(s).refracting.conic = r.values[0]; })
            .labelled("microlens_array lens surface conic").checked(Check_Microlens_Conic),

        // ---- sensor { }: any read-out keyword (bayer to seed) makes the render write the raw ----
        Keyword("pixel_size", B::Sensor, V::Vector2, "0.01", "the pixel pitch, horizontal and vertical (mm)",
                [](CameraSetup& s, R r) { std::copy(r.values, r.values + 2, s.params.sensor.pixel_size_mm); })
            .checked(check_positive_length),
        Keyword("offset", B::Sensor, V::Vector2, "<0, 0>", "the sensor's centre relative to the optical axis (mm)",
                [](CameraSetup& s, R r) { std::copy(r.values, r.values + 2, s.params.sensor.offset_mm); })
            .reserved_word().labelled("sensor offset").checked(check_translation),
        Keyword("angular_response", B::Sensor, V::Number, "0", "the pixels' angular response: cos^e of the incidence angle",
                [](CameraSetup& s, R r) { s.params.sensor.angular_exponent = r.values[0]; })
            .checked(Check_Angular_Exponent),
        Keyword("bayer", B::Sensor, V::Word, "none: R, G and B at every pixel", "the colour filter mosaic",
                [](CameraSetup& s, R r) { chain(s).bayer = kBayerPatterns[(int)r.values[0]]; chain(s).given = true; })
            .words(Bayer_Word).listed_as("and the read-out to the raw: bayer rggb|bggr|grbg|gbrg"),
        Keyword("bit_depth", B::Sensor, V::Number, "12", "the bits of the analogue-to-digital converter",
                [](CameraSetup& s, R r) { chain(s).bit_depth = (int)r.values[0]; chain(s).given = true; })
            .checked(check_bit_depth),
        Keyword("full_well", B::Sensor, V::Number, "10000", "the electrons a pixel holds",
                [](CameraSetup& s, R r) { chain(s).full_well_e = r.values[0]; chain(s).given = true; })
            .checked(check_electrons),
        Keyword("exposure", B::Sensor, V::Number, "E", "the electrons of a pixel whose noise-free value is 1",
                [](CameraSetup& s, R r) {
                    chain(s).exposure_e = r.values[0];
                    chain(s).has_exposure = true;
                    chain(s).given = true;
                })
            .checked(check_electrons),
        Keyword("read_noise", B::Sensor, V::Number, "0", "the read noise (electrons rms)",
                [](CameraSetup& s, R r) { chain(s).read_noise_e = r.values[0]; chain(s).given = true; })
            .checked(check_non_negative),
        Keyword("dark_current", B::Sensor, V::Number, "0", "the dark current (electrons/s)",
                [](CameraSetup& s, R r) { chain(s).dark_current_e_per_s = r.values[0]; chain(s).given = true; })
            .checked(check_non_negative),
        Keyword("exposure_time", B::Sensor, V::Number, "0", "the integration time, for the dark current (s)",
                [](CameraSetup& s, R r) { chain(s).exposure_time_s = r.values[0]; chain(s).given = true; })
            .checked(check_non_negative),
        Keyword("prnu", B::Sensor, V::Number, "0", "photo-response non-uniformity: the rms of the relative gain",
                [](CameraSetup& s, R r) { chain(s).prnu = r.values[0]; chain(s).given = true; })
            .checked(check_non_negative),
        Keyword("dsnu", B::Sensor, V::Number, "0", "dark-signal non-uniformity: the rms of the dark offset (electrons)",
                [](CameraSetup& s, R r) { chain(s).dsnu_e = r.values[0]; chain(s).given = true; })
            .checked(check_non_negative),
        Keyword("black_level", B::Sensor, V::Number, "0", "the DN of no signal",
                [](CameraSetup& s, R r) { chain(s).black_level_dn = (int)r.values[0]; chain(s).given = true; })
            .checked(check_dn),
        Keyword("seed", B::Sensor, V::Number, "0", "the frame's noise",
                [](CameraSetup& s, R r) { chain(s).seed = (std::uint64_t)r.values[0]; chain(s).given = true; })
            .reserved_word().checked(check_whole_number),
    };
}

const KeywordBlockInfo kBlocks[] = {
    {B::None, "", "", nullptr, 0},
    {B::Camera, "camera", "plenoptic camera",
     "and the placement keywords of every camera (location, look_at, sky, right, up, direction, rotate, translate, scale, "
     "matrix, transform)", 0},
    {B::MainLens, "main_lens", "main_lens", nullptr, 0},
    {B::Distortion, "distortion", "distortion", nullptr, 0},
    {B::Prescription, "prescription", "prescription", nullptr, 0},
    {B::Surface, "surface", "surface", nullptr, 0},
    {B::Stop, "stop", "stop", nullptr, 0},
    {B::MicrolensArray, "microlens_array", "microlens_array", nullptr, 0},
    {B::Microlens, "microlens", "microlens_array lens", nullptr, 0},
    {B::MicrolensSurface, "microlens_surface", "microlens_array lens surface", nullptr, 0},
    {B::Sensor, "sensor", "sensor", nullptr, 0},
    {B::WhiteImage, "white_image", "white_image", nullptr, 0},
    {B::Diffraction, "diffraction", "diffraction", nullptr, 1},
    {B::Spectral, "spectral", "spectral", nullptr, 2},
    {B::Errors, "errors", "microlens_array errors", nullptr, 0},
};

} // namespace

const std::vector<Keyword>& keyword_table()
{
    static const std::vector<Keyword> table = make_table();
    return table;
}

const KeywordBlockInfo& keyword_block(KeywordBlock block)
{
    for (const KeywordBlockInfo& info : kBlocks)
        if (info.block == block)
            return info;
    return kBlocks[0];
}

const Keyword *find_keyword(KeywordBlock block, const char *word)
{
    for (const Keyword& keyword : keyword_table())
        if (keyword.block == block && std::strcmp(keyword.word, word) == 0)
            return &keyword;
    return nullptr;
}

const Keyword *find_keyword(const char *word)
{
    for (const Keyword& keyword : keyword_table())
        if (std::strcmp(keyword.word, word) == 0)
            return &keyword;
    return nullptr;
}

std::string allowed_keywords(KeywordBlock block)
{
    std::string list;
    for (const Keyword& keyword : keyword_table())
        if (keyword.block == block)
            list += (list.empty() ? "" : ", ") + std::string(keyword.listed != nullptr ? keyword.listed : keyword.word);
    const char *tail = keyword_block(block).allowed_tail;
    if (tail != nullptr)
        list += (list.empty() ? "" : ", ") + std::string(tail);
    return list;
}

const char *keyword_group_message(KeywordGroup group)
{
    switch (group)
    {
        case G::MainLensKind: return "main_lens takes one of thin_lens, pinhole or thick_lens, not several";
        case G::LensSource: return "main_lens takes one lens_file or one prescription { }, not several";
        case G::Distortion: return "main_lens takes one distortion { }, not several";
        case G::Grid: return "microlens_array takes one of hexagonal or rectangular, not both";
        case G::MicrolensKind: return "microlens_array takes one of pinhole, focal_length, focal_lengths or lens { }, not several";
        case G::MicrolensSurface: return "microlens_array lens takes one surface { } (the cap; its other side is flat)";
        case G::ArrayRotate: return "microlens_array takes rotate once (about x, then y, then z, in degrees)";
        case G::ArrayTranslate: return "microlens_array takes translate once (mm, after the rotation)";
        case G::ArrayErrors: return "microlens_array takes one of errors { } or lens_table, once";
        case G::None: break;
    }
    return "";
}

std::string needed_keywords(KeywordBlock block)
{
    std::vector<const char *> needed;
    for (const Keyword& keyword : keyword_table())
        if (keyword.block == block && keyword.needed)
            needed.push_back(keyword.word);
    std::string text;
    for (size_t i = 0; i < needed.size(); i++)
        text += std::string(i == 0 ? "" : i + 1 == needed.size() ? " and " : ", ") + needed[i];
    return text;
}

std::string keyword_words(const Keyword& keyword, const char *separator)
{
    std::string text;
    for (int i = 0; keyword.word_at != nullptr && keyword.word_at(i) != nullptr; i++)
        text += std::string(i == 0 ? "" : separator) + keyword.word_at(i);
    return text;
}

const char *keyword_value_name(KeywordValue value)
{
    switch (value)
    {
        case V::Flag: return "flag";
        case V::Number: return "number";
        case V::Vector2: return "vector2";
        case V::Vector3: return "vector3";
        case V::Vector6: return "vector6";
        case V::OnOff: return "on/off";
        case V::Word: return "word";
        case V::String: return "string";
        case V::ResponseFile: return "string";
        case V::Block: return "block";
        case V::Samples: return "samples";
        case V::FNumbers: return "f_numbers";
        case V::FloatList: return "float_list";
        case V::NumberPair: return "number_pair";
        case V::LensTable: return "string";
    }
    return "";
}

} // namespace plenoptic
