// SPDX-License-Identifier: AGPL-3.0-or-later
// The plenoptic camera model: everything precomputed once from checked parameters.

#ifndef PLENOPTIC_MODEL_H
#define PLENOPTIC_MODEL_H

#include <memory>
#include <string>
#include <vector>

#include "plenoptic/lens/main_lens.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/lens/lit_area.h"
#include "plenoptic/lens/pupil_bounds.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

// Most rings of neighbouring lenses whose light a pixel may receive when microimages overlap.
const int kMaxOverlapRings = 8;
// Lenses in that many rings of a rectangular grid (the larger of the two grids): (2*8+1)^2.
const int kMaxOverlapLenses = (2 * kMaxOverlapRings + 1) * (2 * kMaxOverlapRings + 1);

// Pose of the microlens array in the optics frame: q_optics = centre_mm + rotation * q_local.
struct ArrayPose {
    Mat3 rotation;   // array-local -> optics frame, Rz * Ry * Rx
    Vec3 centre_mm;  // where the array's lens (0, 0) sits
    Vec3 normal;     // rotation * (0, 0, 1): towards the scene
    bool tilted;     // rotated about x or y: the array plane is not parallel to the sensor
    double tilt_sine;// sine of the angle between the array's normal and the optical axis
};

// Above this tilt (sine of the angle, about 11.5 degrees) a pixel's overlap lenses are not pruned.
const double kMaxPrunedTiltSine = 0.2;

// The sensor's picture: its size in pixels. The scene parser knows no image size (POV-Ray's +W
// and +H come with the render), so a model is made without one (0 x 0) and a render's camera
// carries its own (with_film): everything that maps pixels to sensor points reads it here.
struct Film {
    int width;
    int height;
};

// Optics frame: origin at the main-lens centre (a real lens's rear vertex; the array centre when
// there is no main lens), +z towards the scene, +x right, +y up; millimetres throughout.
struct Model {
    CameraParams spec;           // the checked parameters the camera was made from
    double mm_per_unit;
    // What a pixel measures (camera/radiometry.h); under Irradiance each passing sample's colour
    // is weighted by irradiance_weight with K = irradiance_k_mm2 (0 under Flat).
    Radiometry radiometry;
    double irradiance_k_mm2;
    double angular_exponent;     // sensor angular_response n: each sample also weighs cos^n(incidence)

    // The main lens (it answers for its kind: lens/main_lens.h); nullptr without one.
    std::shared_ptr<const MainLens> lens;
    double focal_length_mm;      // F (a real lens's effective focal length); 0 for pinhole and none
    double aperture_mm;          // A (diameter; a real lens's stop); 0 for pinhole and none
    double f_number;             // F / A (a real lens's: F / entrance-pupil diameter); 0 for pinhole and none
    double distance_mm;          // D (from a real lens's rear vertex); 0 without main lens
    // A thin lens's parametric distortion (lens/distortion.h), on the plane z = -D.
    bool has_distortion;
    DistortionParams distortion;
    // A real lens (thick_lens or prescription): its surfaces as used (stop sized, iris applied),
    // their paraxial data, the file they came from ("" when inline), and its length from the
    // front vertex (where the scene's location puts it) to the rear vertex (the frame's origin).
    Prescription prescription;
    ParaxialData paraxial;
    std::string lens_file;
    double lens_length_mm;
    // Where light passes a traced real lens, for points of the sensor (no array) or of the array
    // plane: what ray generation samples, and what the overlap bound reaches. nullptr otherwise.
    std::shared_ptr<const PupilBounds> pupil_bounds;
    // Without an array, behind a traced lens with a round stop: the lit area of the exit pupil's
    // plane per sensor radius (under irradiance radiometry weighted as the samples are), which
    // replaces the per-pixel vignetting probes. nullptr otherwise.
    std::shared_ptr<const LitAreaTable> lit_area;
    bool has_focus_distance;     // D came from focus_distance
    double focus_distance_units; // as given; 0 when D was given directly

    GridType grid;               // None: no microlens array
    double pitch_mm;
    MicrolensType microlens;
    int lens_type_count;         // 1, or 3 for multi-focus arrays
    double microlens_focal_mm[3];// per lens type; 0 for pinholes
    double array_distance_mm;    // d; 0 without array
    ArrayPose pose;
    double cell_inradius_mm;     // of a lens's lattice cell
    double cell_circumradius_mm;

    Film film;                   // the picture's size in pixels (0 x 0 until with_film)
    double sensor_z_mm;          // -(D + d); -D without array; -d without main lens
    double pixel_size_mm[2];
    double sensor_offset_mm[2];

    // Overlapping microimages: modelled only when the parameters make overlap possible.
    bool model_overlap;
    int overlap_rings;           // rings of neighbours a pixel may receive light through
    bool overlap_rings_capped;   // the bound asked for more than kMaxOverlapRings

    bool adaptive;
    int samples_min;             // == samples_max when not adaptive
    int samples_max;
    double confidence;
    double variance;
    std::vector<double> thresholds; // adaptive stop thresholds, index n-1 for n samples
};

// Builds the model from parameters that passed check_camera. Pure: no image size, no state.
Model make_model(const CameraParams& params);

// The same camera taking a picture of width x height pixels.
Model with_film(Model model, int width, int height);
// The same camera, film included, with its main lens's aperture set for f-number N (a thin lens's
// A = F / N; a real lens's stop sized for it): what a white image at N is taken with. N must be
// one the lens can take (check_white_image_f_numbers).
Model with_f_number(const Model& camera, double f_number);

// Legal but implausible parameters, one sentence each (empty when nothing is odd).
std::vector<std::string> warnings(const Model& model);
// The warning for a real lens whose stop, as written (no f_number or aperture), does not limit the
// axial beam: names the stop, the limiting surface (row, line) and the f-number the lens works at;
// "" when the stop limits it.
std::string limiting_aperture_warning(const Model& model);

// Rotation about x, then y, then z, in degrees: v -> Rz * Ry * Rx * v, with the same
// matrices as POV-Ray's Compute_Rotation_Transform (which applies them to row vectors).
// Multiples of 90 degrees are exact.
Mat3 rotation_from_degrees(const double degrees[3]);

// Main-lens -> array and array -> sensor distances measured at the array centre, including the
// array's z translation. The first is measured from the main lens's exit-pupil centre, from which
// microimage centres are projected (the lens's plane for a thin lens, the pinhole); without a main
// lens it is 0.
double effective_main_distance_mm(const Model& model);
double effective_array_distance_mm(const Model& model);

} // namespace plenoptic

#endif
