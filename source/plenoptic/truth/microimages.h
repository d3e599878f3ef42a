// SPDX-License-Identifier: AGPL-3.0-or-later
// Ground truth of the microimages (`<image>.microimages.csv`): where the light of a
// white scene falls behind each microlens, computed through the camera's own rays. Behind a real
// main lens (pupil aberration, vignetting, distortion) the microimages are no longer the
// projections of the lens centres from the exit pupil's centre: their centres leave the lattice
// and the corner ones are cut to cat's eyes.

#ifndef PLENOPTIC_MICROIMAGES_H
#define PLENOPTIC_MICROIMAGES_H

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// One lens's microimage in a white scene (the same radiance from every direction).
struct MicroimageTruth {
    LensIndex lens;        // row form (k, l)
    bool lit;              // false: no light through this lens reaches the sensor (u, v unused)
    double u_px, v_px;     // centroid of that light on the sensor, pixels, centre convention
    // The light through the lens over the light a fully lit microimage cell would get: the area
    // integral, over the sensor, of the fraction E(x) of the lens's aperture through which sensor
    // point x receives light, divided by the area of the lens's microimage cell (the lens's cell
    // projected from the exit pupil's centre). 1 for a cell lit everywhere; the lit fraction of the
    // cell for pinhole microlenses; above 1 only where microimages overlap their neighbours.
    double lit_fraction;
};

// How finely each microimage is integrated.
struct MicroimageOptions {
    // Boundary directions around the start point; the region is integrated in polar form
    // (area = 1/2 sum r^2 dtheta, moments = 1/3 sum r^3 (cos, sin) dtheta), which the trapezoid
    // rule integrates spectrally for smooth boundaries.
    int azimuths;
    // Each boundary radius is found to within a bracket this narrow (pixels): with
    // reuse_neighbours the step of the grid 0, tolerance_px, 2 tolerance_px, ... that holds the
    // boundary, else a bisected bracket; the radius is the bracket's middle.
    double tolerance_px;
    // Thin microlenses: aperture points of the lens, aperture_points x aperture_points on the
    // renderer's own uniform map of the cell (pairs symmetric about the centre, so terms linear in
    // the aperture point cancel); pinhole microlenses use the centre only. Behind a vignetting
    // lens 3 x 3 lands within 0.01 px of 8 x 8 (the unit tests measure it).
    int aperture_points;
    // Threads measuring lenses (0: one per hardware thread); the result does not depend on it.
    int threads;
    // Seek each boundary radius near the same radius of the previous lens of its row (each
    // prediction checked by the renderer's rays, each answer as close to a crossing as without);
    // false: every lens from scratch (the reference the unit tests compare against).
    bool reuse_neighbours;
    // Refracting microlenses on an array without manufacturing errors: the lenses k, l that are
    // multiples of anchor_step (even, at least 4) are measured as anchors, and the others
    // interpolated between them (a cubic each way through the 4 x 4 nearest) wherever the anchors'
    // fourth differences put the cubic's error below 5e-4 px and 5e-5 of lit fraction; the lenses
    // left try anchors at half the step, and so on down to 4; those left then, and pictures with
    // too few lenses for anchors to pay, are measured. 0: every lens measured. Other microlenses
    // and arrays with errors: every lens measured, whatever this is.
    int anchor_step = 0;
    // Refracting microlenses on an array with manufacturing errors: 0 (the default) measures every
    // lens. At least 4 (with anchor_step at least 4), an approximation, 3.4 to 90 times faster:
    // each lens is the ideal lens interpolated where it sits, corrected to second order in each of
    // its errors (its own dz, focal length and tilt, its neighbours' displacements) by differences
    // measured at Jacobian anchors this many lenses apart, where their cubic vouches for it; the
    // other lenses are measured. Within 0.013 px and 0.004 of lit fraction of measuring each lens
    // behind the 22 mm wide-angle (as close to brute force as measuring is), 0.02 px and 0.01 behind
    // the unit tests' triplet, where the neighbours' displacements cut lit parts of the cells
    // (BENCHMARKS "Refracting microlenses with errors, corrected").
    int error_anchor_step = 0;
    // Refracting microlenses: cell points a side (at least aperture_points).
    int refracting_points = 24;
    // Refracting microlenses on an ideal array whose lens (0, 0) sits on the optical axis (hexagonal
    // or square lattice, its rows along the sensor's x or y axis, not tilted, no manufacturing
    // errors): measure only the lenses of the quarter x >= 0, y >= 0 of the array's frame, and give
    // every other lens the microimage of its mirror image there, mirrored (the camera and the cell
    // rule are symmetric under those mirrors, so this is what measuring the lens gives, to
    // rounding). Such an array turned about the axis by other than a multiple of 90 degrees, or
    // moved across it: its anchors are measured in the same array turned back onto the axis (as
    // above), each lens interpolated where it sits there and turned back (the same rule in a
    // turned frame: the same accuracy, not the same bits). false: each lens measured where it is.
    bool symmetry = true;
};

// Called now and then (about every tenth of the lenses) with the lenses done and their number.
typedef std::function<void(std::size_t done, std::size_t total)> MicroimageProgress;
// Polled between lenses: true stops the work (microimage_truth then returns nothing).
typedef std::function<bool()> MicroimageCancel;

MicroimageOptions default_microimage_options();

// The lenses whose microimage centres on the metadata's lattice lie in the W x H picture, each
// with its microimage measured in the model's white scene, row by row (l, then k, increasing).
// A sensor point receives light through the lens exactly when the renderer's ray from it through
// that lens passes every aperture (generate_ray with the lens forced) and, when the camera does
// not model overlapping microimages, when the lens is the point's own lens. Microimages are not
// cut at the picture's edge. Each microimage is taken star-shaped about its start point (the
// lattice centre, or the centroid of a coarse search when that point is dark): the region
// between that point and the first boundary crossing along each direction. Needs a main lens and
// an array (empty otherwise). Deterministic: each lens's result depends on that lens alone (not on the
// thread count nor on which lenses are measured with it) wherever each direction crosses its boundary once.
// With `through` (the same camera at another wavelength: at_wavelength), the lenses and their
// start points are still this camera's, and the light is traced through `through`: the same lenses
// in the same order, their microimages at that wavelength.
// `work` (if given) receives how the lenses were found (anchors, MicroimageOptions::anchor_step).
struct MicroimageWork {
    std::size_t anchors = 0;       // lenses measured as anchors (0: no interpolation)
    std::size_t interpolated = 0;  // lenses of the picture interpolated between anchors
    std::size_t measured = 0;      // lenses of the picture measured each
    // With MicroimageOptions::symmetry in use: the lenses actually measured (quarter lenses, for the
    // anchors and the lenses measured each; on an array turned or moved, the anchors' quarter lenses
    // on the axis and the lenses measured where they are); 0 otherwise.
    std::size_t quarter_lenses = 0;
    // Refracting microlenses with manufacturing errors: the lenses interpolated as the ideal lens
    // that sits where each sits and corrected for their errors (`interpolated` counts them too), and
    // the Jacobian anchors measured for the corrections of their own dz, focal length and tilt.
    std::size_t corrected = 0;
    std::size_t error_anchors = 0;
};
std::vector<MicroimageTruth> microimage_truth(const PlenopticCamera& model, const MicroimageOptions& options,
                                              const MicroimageProgress& progress = MicroimageProgress(),
                                              const MicroimageCancel& cancelled = MicroimageCancel(),
                                              const PlenopticCamera* through = nullptr,
                                              MicroimageWork* work = nullptr);

// The given lenses, each measured (never interpolated between anchors), in the given order: what
// microimage_truth gives a lens with anchor_step 0, whichever lenses are measured with it.
std::vector<MicroimageTruth> measured_microimages(const PlenopticCamera& model, const std::vector<LensIndex>& lenses,
                                                  const MicroimageOptions& options,
                                                  const PlenopticCamera* through = nullptr);

// Least-squares lattice through the lit centres: (u, v) = origin + k_s a + l b in skew indices,
// as the metadata's microimage_lattice, and how far the centres lie from it.
struct LatticeFit {
    bool valid;                // at least three lit lenses not in one row
    double origin_px[2];
    double basis_a_px[2];
    double basis_b_px[2];
    std::size_t lenses;        // lit lenses fitted
    double rms_residual_px;    // root mean square of |centre - fit|
    double max_residual_px;
    LensIndex worst;           // where the largest residual is
};

LatticeFit fit_microimage_lattice(const PlenopticCamera& model, const std::vector<MicroimageTruth>& truth);

// The fit's residual for one lens (centre - fit), pixels.
Vec2 lattice_residual(const PlenopticCamera& model, const LatticeFit& fit, const MicroimageTruth& lens);

// What the metadata says about the microimages file (docs/metadata.md, "microimages").
struct MicroimageSummary {
    std::string file;              // the CSV's name, beside the image
    std::size_t lenses, lit_lenses;
    MicroimageOptions options;
    LatticeFit fit;
    // How far the lit centres lie from the metadata's microimage_lattice (the paraxial lattice).
    double from_lattice_rms_px, from_lattice_max_px;
    // With spectral sampling, the centres per channel (u_r, v_r, u_g, v_g, u_b, v_b columns) at
    // these wavelengths (channel_wavelengths_nm); 0: none.
    bool per_channel = false;
    double channel_wavelengths_nm[3] = {0, 0, 0};
    // The array has manufacturing errors: the file has each lens's (dx_mm ... tilt_azimuth_deg).
    bool lens_errors = false;
    // How the lenses were found (set by the caller from microimage_truth's `work`): with anchors,
    // the metadata's integration says so.
    MicroimageWork work;
};

MicroimageSummary summarise_microimages(const PlenopticCamera& model, const std::vector<MicroimageTruth>& truth,
                                        const MicroimageOptions& options, const std::string& file);

// The CSV text: a header line "k,l,u,v,lit_fraction,residual_u,residual_v", then one line per
// lens (row-form indices, centre-convention pixels, the residuals from the fit); u, v and the
// residuals are empty for a dark lens, the residuals also when the fit is not valid. With three
// `channels` (the same lenses measured at the R, G and B wavelengths), six more columns,
// u_r,v_r,u_g,v_g,u_b,v_b, empty where that channel's microimage is dark. With manufacturing errors
// (array/lens_errors.h), each lens as it is: dx_mm,dy_mm,dz_mm,focal_length_mm,tilt_deg,
// tilt_azimuth_deg (the focal length empty for pinholes), which lens_table reads back. Numbers in the shortest
// form that reads back to the same double.
std::string microimages_csv(const PlenopticCamera& model, const std::vector<MicroimageTruth>& truth, const LatticeFit& fit,
                            const std::vector<std::vector<MicroimageTruth>>& channels =
                                std::vector<std::vector<MicroimageTruth>>());
// The same text in pieces, for writing it as it is made (a Lytro-class raw's is some 25 MB): the
// header line, and the lines of lenses begin .. end - 1.
std::string microimages_csv_header(const PlenopticCamera& model, bool per_channel);
std::string microimages_csv_lines(const PlenopticCamera& model, const std::vector<MicroimageTruth>& truth,
                                  const LatticeFit& fit, const std::vector<std::vector<MicroimageTruth>>& channels,
                                  std::size_t begin, std::size_t end);

} // namespace plenoptic

#endif
