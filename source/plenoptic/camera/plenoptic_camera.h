// SPDX-License-Identifier: AGPL-3.0-or-later
// The plenoptic camera: its parts (main lens, microlens array, sensor, sampling), made once from
// checked parameters.

#ifndef PLENOPTIC_MODEL_H
#define PLENOPTIC_MODEL_H

#include <memory>
#include <string>
#include <vector>

#include "plenoptic/array/microlens_array.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/camera/spectral_bands.h"
#include "plenoptic/lens/lit_area.h"
#include "plenoptic/lens/pupil_bounds.h"
#include "plenoptic/core/vec.h"
#include "plenoptic/sensor/sensor_chain.h"

namespace plenoptic {

// Most rings of neighbouring lenses whose light a pixel may receive when microimages overlap.
const int kMaxOverlapRings = 8;
// Lenses in that many rings of a rectangular grid (the larger of the two grids): (2*8+1)^2.
const int kMaxOverlapLenses = (2 * kMaxOverlapRings + 1) * (2 * kMaxOverlapRings + 1);

// Above this tilt (sine of the angle, about 11.5 degrees) a pixel's overlap lenses are not pruned.
const double kMaxPrunedTiltSine = 0.2;

// The sensor's picture: its size in pixels. The scene parser knows no image size (POV-Ray's +W
// and +H come with the render), so a model is made without one (0 x 0) and a render's camera
// carries its own (with_film): everything that maps pixels to sensor points reads it here.
struct Film {
    int width;
    int height;
};

// Overlapping microimages: modelled only when the camera's geometry makes overlap possible.
struct Overlap {
    bool modelled = false;
    int rings = 0;  // rings of neighbours a pixel may receive light through
    bool rings_capped = false;  // the bound asked for more than kMaxOverlapRings
    // Refracting lenses: how far from a lens's microimage centre its light lands on the sensor
    // (traced, see plenoptic_camera.cpp: traced_reach_mm), by which a pixel's lenses are pruned;
    // 0 for the other lenses, whose first-order bound prunes them.
    double reach_mm = 0;
};

// A point of the picture in the centre convention used by the metadata (pixel (i, j)'s centre is
// at (u, v) = (i, j)), and whether it lies inside the image.
struct PixelPoint {
    double u, v;
    bool inside;
};

// The sensor: its picture (film), its plane and pixel grid, and what a pixel measures.
struct Sensor {
    Film film = Film{0, 0};  // the picture's size in pixels (0 x 0 until with_film)
    double z_mm = 0;  // -(D + d); -D without array; -d without main lens
    double pixel_size_mm[2] = {0, 0};
    double offset_mm[2] = {0, 0};
    // What a pixel measures (camera/radiometry.h); under Irradiance each passing sample's colour
    // is weighted by irradiance_weight with K = irradiance_k_mm2 (0 under Flat).
    Radiometry radiometry = Radiometry::Flat;
    double irradiance_k_mm2 = 0;
    double angular_exponent = 0;  // angular_response n: each sample also weighs cos^n(incidence)

    // Point on the sensor (optics frame, mm) at continuous pixel coordinates (pu, pv), where pixel
    // (i, j) spans [i, i+1) x [j, j+1); (i + 0.5, j + 0.5) is its centre:
    //   x = -(pu - W/2) * sx + ox,  y = (pv - H/2) * sy + oy,  z = sensor plane.
    Vec3 point(double pu, double pv) const;
    // The inverse, in the centre convention.
    PixelPoint to_pixel(double x_mm, double y_mm) const;
    // Where the optical axis meets the sensor, centre convention.
    Vec2 principal_point_px() const;
    // The metadata's sensor section: its plane and pixel grid, its radiometry with the camera's
    // reference projected solid angle (camera/radiometry.h; 0 or less: null), and the read-out
    // `chain` with the raw's file name (sensor/sensor_chain.h: read_out_metadata).
    MetadataJson metadata(double projected_solid_angle_sr, const SensorChainParams& chain,
                          const std::string& raw_file) const;
};

// How many samples a pixel takes (fixed, or adaptive between a minimum and a maximum).
struct Sampling {
    bool adaptive = false;
    int samples_min = 0;  // == samples_max when not adaptive
    int samples_max = 0;
    double confidence = 0;
    double variance = 0;
    std::vector<double> thresholds; // adaptive stop thresholds, index n-1 for n samples
    // Samples aimed where light passes (camera/aim.h: camera_can_aim); false samples every pixel
    // and cell uniformly.
    bool aim = false;
    // The metadata's samples section.
    MetadataJson metadata() const;
};

struct OpticsRay;
struct CameraSample;
struct PixelHit;
struct SpectralCameras;

// The plenoptic camera: a main lens, an optional microlens array, a sensor with its film, and the
// sampling settings, each part holding its own data; everything precomputed once from checked
// parameters. The camera answers for itself (generate_ray, chief_ray, project, receives_light);
// the functions that do the work live with their concern (camera/rays, projection/, camera/pixel)
// and take the camera.
//
// Optics frame: origin at the main-lens centre (a real lens's rear vertex; the array centre when
// there is no main lens), +z towards the scene, +x right, +y up; millimetres throughout.
struct PlenopticCamera {
    CameraParams spec;           // the checked parameters the camera was made from
    double mm_per_unit = 0;

    // The main lens (it answers for its kind: lens/main_lens.h); nullptr without one. D is where
    // this camera holds it: from its rear vertex (its plane) to the array, or to the sensor.
    std::shared_ptr<const MainLens> lens;
    double distance_mm = 0;  // D; 0 without main lens
    bool has_focus_distance = false;  // D came from focus_distance
    double focus_distance_units = 0;  // as given; 0 when D was given directly
    // Where light passes a traced real lens, for points of the sensor (no array) or of the array
    // plane: what ray generation samples, and what the overlap bound reaches. nullptr otherwise.
    // The lens makes it for the plane this camera puts behind it.
    std::shared_ptr<const PupilBounds> pupil_bounds;
    // Without an array, behind a traced lens with a round stop: the lit area of the exit pupil's
    // plane per sensor radius (under irradiance radiometry weighted as the samples are), which
    // replaces the per-pixel vignetting probes. nullptr otherwise.
    std::shared_ptr<const LitAreaTable> lit_area;

    MicrolensArray array;
    Overlap overlap;
    Sensor sensor;
    Sampling sampling;
    // Spectral sampling (`spectral N`, camera/spectral_bands.h): the bands and this camera at each
    // band's wavelength, which traces that band's samples (camera/pixel.h); nullptr without it.
    // This camera itself is the camera at the d line: chief rays, projection and the ground truth
    // ask it.
    std::shared_ptr<const SpectralCameras> spectral;

    // What the main lens says, 0 (or empty) without one: F (a real lens's effective focal
    // length), A (its diameter; a real lens's stop), the f-number (a real lens's: F / entrance-pupil
    // diameter); a real lens's surfaces as used and their paraxial data, the file they came from
    // ("" when inline), and its length from the front vertex (where the scene's location puts it)
    // to the rear vertex (the frame's origin); a thin lens's parametric distortion (nullptr: none).
    double focal_length_mm() const { return lens ? lens->focal_length_mm() : 0.0; }
    double aperture_mm() const { return lens ? lens->aperture_mm() : 0.0; }
    double f_number() const { return lens ? lens->f_number() : 0.0; }
    const Prescription& prescription() const;
    const ParaxialData& paraxial() const;
    const std::string& lens_file() const;
    double lens_length_mm() const { return paraxial().valid ? paraxial().rear_vertex_z : 0.0; }
    const DistortionParams* distortion() const { return lens ? lens->distortion() : nullptr; }

    // The camera's questions, answered where their concern lives:
    // one sample's ray of pixel (i, j) (camera/rays.cpp: generate_ray);
    OpticsRay generate_ray(int i, int j, const CameraSample& sample) const;
    // the chief ray of pixel (i, j) (camera/rays.cpp: chief_ray);
    OpticsRay chief_ray(int i, int j) const;
    // where a scene point (optics frame, mm) images on the sensor (projection/: forward_project);
    std::vector<PixelHit> project(Vec3 point_mm) const;
    // whether pixel (i, j) can receive light at all (camera/pixel.h: pixel_receives_light).
    bool receives_light(int i, int j) const;
};

// The cameras of spectral sampling.
struct SpectralCameras {
    std::vector<SpectralBand> bands;
    std::vector<PlenopticCamera> cameras;  // cameras[b]: the camera at bands[b].wavelength_nm
};

// Builds the camera from parameters that passed check_camera. Pure: no image size, no state.
PlenopticCamera make_camera(const CameraParams& params);

// The same camera at a wavelength (nm): its main lens's glass and its microlenses' at their
// indices there (MainLens::at_wavelength, MicrolensArray::at_wavelength), with the pupil bounds, the
// lit-area table and the overlap bound that lens and array need; every position (D, d, the sensor),
// the stop and the sampling as they are, since glass, not the camera's build, changes with the
// wavelength. Without spectral cameras of its own. The camera itself (less them) when nothing in it
// disperses.
PlenopticCamera at_wavelength(const PlenopticCamera& camera, double wavelength_nm);

// The same camera taking a picture of width x height pixels.
PlenopticCamera with_film(PlenopticCamera model, int width, int height);
// The same camera, film included, with its main lens's aperture set for f-number N (a thin lens's
// A = F / N; a real lens's stop sized for it): what a white image at N is taken with. N must be
// one the lens can take (check_white_image_f_numbers).
PlenopticCamera with_f_number(const PlenopticCamera& camera, double f_number);

// Legal but implausible parameters, one sentence each (empty when nothing is odd).
std::vector<std::string> warnings(const PlenopticCamera& model);
// The warning for a real lens whose stop, as written (no f_number or aperture), does not limit the
// axial beam: names the stop, the limiting surface (row, line) and the f-number the lens works at;
// "" when the stop limits it.
std::string limiting_aperture_warning(const PlenopticCamera& model);

// Main-lens -> array and array -> sensor distances measured at the array centre, including the
// array's z translation. The first is measured from the main lens's exit-pupil centre, from which
// microimage centres are projected (the lens's plane for a thin lens, the pinhole); without a main
// lens it is 0.
double effective_main_distance_mm(const PlenopticCamera& model);
double effective_array_distance_mm(const PlenopticCamera& model);

} // namespace plenoptic

#endif
