// SPDX-License-Identifier: AGPL-3.0-or-later
// The main lens's specification: the stop the camera uses, the image distance, the lens object.

#include "plenoptic/lens/main_lens_params.h"

namespace plenoptic {

Prescription effective_prescription(const MainLensParams& main)
{
    Prescription lens = main.prescription;
    lens.blades = main.blades;
    lens.blade_rotation_deg = main.blade_rotation_deg;
    double stop_mm = 0;
    if (main.has_aperture)
        stop_mm = main.aperture_mm;
    else if (main.has_f_number)
        stop_mm = stop_diameter_for_f_number(main.prescription, main.f_number);
    if (stop_mm > 0)
        for (LensSurface& surface : lens.surfaces)
            if (surface.stop)
                surface.aperture_mm = stop_mm;
    return lens;
}

double main_lens_distance_mm(const MainLensParams& main, double mm_per_unit)
{
    if (!main.has_focus_distance)
        return main.distance_mm;
    const double z_mm = main.focus_distance_units * mm_per_unit;
    if (is_prescription_type(main.type))
        return paraxial_image_distance(main.prescription, z_mm).mm;
    // 1/F = 1/z + 1/D, written so that a huge z gives D -> F without overflow.
    const double f = main.focal_length_mm;
    return f / (1.0 - f / z_mm);
}

std::shared_ptr<const MainLens> make_main_lens(const MainLensParams& p, double distance_mm)
{
    if (!p.given)
        return nullptr;
    switch (p.type) {
    case MainLensType::Pinhole:
        return make_pinhole_lens();
    case MainLensType::ThinLens: {
        const double aperture = thin_lens_aperture_mm(p);
        const double f_number = p.has_f_number ? p.f_number : p.focal_length_mm / aperture;
        return make_thin_lens(p.focal_length_mm, aperture, f_number, p.has_distortion ? &p.distortion : nullptr,
                              -distance_mm);
    }
    case MainLensType::ThickLens:
    case MainLensType::Prescription:
        return make_prescription_lens(effective_prescription(p), 0, p.type == MainLensType::Prescription, distance_mm);
    case MainLensType::None:
        break;
    }
    return nullptr;
}

} // namespace plenoptic
