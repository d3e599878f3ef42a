// SPDX-License-Identifier: AGPL-3.0-or-later
// The main lens's specification as the parser fills it (main_lens { ... }), what follows from it
// alone (the stop the camera uses, the distance to the image plane), and the one place where a
// specification becomes a lens object of its kind (make_main_lens). The camera's checks of the
// block live with the other parameter checks (camera/params.h).

#ifndef PLENOPTIC_MAIN_LENS_PARAMS_H
#define PLENOPTIC_MAIN_LENS_PARAMS_H

#include <memory>
#include <string>

#include "plenoptic/lens/distortion.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/prescription.h"

namespace plenoptic {

// Pinhole and ThinLens are ideal; ThickLens is a prescription's paraxial equivalent;
// Prescription is the real lens, traced surface by surface.
enum class MainLensType { None, Pinhole, ThinLens, ThickLens, Prescription };

// Most blades of a polygonal iris.
const int kMaxBlades = 1000;

// main_lens { ... }. `given` is false when the scene has no main_lens block (type stays None).
struct MainLensParams {
    bool given = false;
    // None inside a given block until a thin_lens, pinhole or thick_lens keyword is read; a
    // lens_file or prescription { } without one of them makes it Prescription when the block closes.
    MainLensType type = MainLensType::None;
    bool has_prescription = false;          // lens_file or prescription { } was read
    Prescription prescription;              // its surfaces (blades below are applied by the model)
    std::string lens_file;                  // the name as the scene wrote it; "" for an inline prescription
    int blades = 0;                         // polygonal iris at the stop; 0: round
    double blade_rotation_deg = 0;
    bool has_focal_length = false;
    double focal_length_mm = 0;             // F
    bool has_f_number = false;
    double f_number = 0;                    // N = F / A
    bool has_aperture = false;
    double aperture_mm = 0;                 // A, diameter (of the stop, for a prescription)
    bool has_focus_distance = false;
    double focus_distance_units = 0;        // scene units in front of the lens (its front vertex)
    bool has_distance = false;
    double distance_mm = 0;                 // D: main lens (rear vertex) -> array (-> sensor without array)
    // distortion { radial <k1, k2, k3> tangential <p1, p2> } (thin lens only; lens/distortion.h)
    bool has_distortion = false;
    DistortionParams distortion = {{0, 0, 0}, {0, 0}};
};

// Whether the main lens is given by a prescription (traced exactly, or as its thick lens).
inline bool is_prescription_type(MainLensType type)
{
    return type == MainLensType::ThickLens || type == MainLensType::Prescription;
}

// Whether a main lens is given and is a pinhole (no aperture of a size), and whether it has an
// aperture of a size (a thin lens or a real one).
inline bool is_pinhole(const MainLensParams& main) { return main.given && main.type == MainLensType::Pinhole; }
inline bool has_sized_aperture(const MainLensParams& main)
{
    return main.given && (main.type == MainLensType::ThinLens || is_prescription_type(main.type));
}

// A prescription main lens as the camera uses it: its surfaces with the iris applied and the
// stop at the diameter that `aperture` or `f_number` asks for (as written when neither is given).
Prescription effective_prescription(const MainLensParams& main);

// A thin lens's aperture diameter A: as given, or F / N (the one place it is derived).
inline double thin_lens_aperture_mm(const MainLensParams& main)
{
    return main.has_aperture ? main.aperture_mm : main.focal_length_mm / main.f_number;
}

// D for a main lens whose block passed check_main_lens: as given, or the paraxial image distance
// of focus_distance (thin lens: F z / (z - F); prescription: from its rear vertex).
double main_lens_distance_mm(const MainLensParams& main, double mm_per_unit);

// The main lens of a checked specification (nullptr for none). A lens knows only itself, and D
// (distance_mm: main lens to array, or sensor) only for a thin lens's distortion, which acts on
// the plane z = -D, and for a real lens's pupils (the images of the aperture that limits the
// axial beam converging at z = -D).
std::shared_ptr<const MainLens> make_main_lens(const MainLensParams& params, double distance_mm);

} // namespace plenoptic

#endif
