// SPDX-License-Identifier: AGPL-3.0-or-later
// Builds the plenoptic camera model once from checked parameters; warnings for odd but legal ones.

#include "plenoptic/camera/plenoptic_camera.h"

#include <algorithm>
#include <cmath>

#include "plenoptic/array/refracting_microlens.h"
#include "plenoptic/core/json.h"
#include "plenoptic/core/lattice.h"
#include "plenoptic/camera/radiometry.h"
#include "plenoptic/core/sampling.h"
#include "plenoptic/camera/aim.h"

namespace plenoptic {

namespace {

// Everything the overlap bound needs, measured at the array centre (see docs/camera-internals.md).
struct OverlapGeometry {
    double magnification;  // k = d / D: microimage-lattice scale is 1 + k
    double disc_mm;        // radius of the main aperture's image through a lens centre
    double blur_mm;        // reach of a lens cell's light beyond that, on the sensor
    double blur_inradius_mm; // same with the cell's inradius (a round lens of diameter p)
    double cell_mm;        // inradius of a microimage cell on the sensor
    double shift_mm;       // how far manufacturing errors can move a microimage from its cell
    double traced_mm;      // refracting lenses: the traced reach (traced_reach_mm), else 0
};

// Refracting lenses: how far from the microimage centre of a sample's lens (the lens whose cell holds
// the point where the sample's line crosses the array's plane on the sensor side) its light can land
// on the sensor. A path may cross into a neighbour's glass and leave through its surface, and the
// caps' spherical aberration is not first-order optics, so the reach is traced: light from a grid
// over the exit pupil's disc (at the array's centre) through the lens at the array's centre, over
// its cell grown by the glass's thickness (towards_sensor), landed on the sensor, measured from the
// microimage centre of the lens its sensor-side line enters; with a margin for the grids' spacing
// (the rings it gives are checked against brute force in the unit tests). 0 for other lenses.
const int kReachPupilGrid = 12, kReachCellGrid = 32;

double traced_reach_of_centre_lens(const PlenopticCamera& m)
{
    const LensIndex lens{0, 0};
    const Vec3 c = m.array.centre_mm(lens);
    const Vec3 e = m.lens->exit_pupil_centre();
    PupilDisc disc{e, m.lens->exit_pupil_radius()};
    if (m.pupil_bounds)
        disc = m.pupil_bounds->disc_for(c);
    if (!(disc.radius > 0))
        return 0;
    const double grown = m.array.cell_circumradius_mm + m.array.microlens->thickness_mm();
    double reach = 0;
    for (int a = 0; a <= kReachPupilGrid; ++a) {
        for (int b = 0; b <= kReachPupilGrid; ++b) {
            const Vec2 on = concentric_disc(double(a) / kReachPupilGrid, double(b) / kReachPupilGrid);
            const Vec3 q{disc.centre.x + disc.radius * on.x, disc.centre.y + disc.radius * on.y, disc.centre.z};
            for (int i = 0; i <= kReachCellGrid; ++i) {
                for (int j = 0; j <= kReachCellGrid; ++j) {
                    const Vec3 local{grown * (2.0 * i / kReachCellGrid - 1), grown * (2.0 * j / kReachCellGrid - 1), 0};
                    const Vec3 h = m.array.to_optics(m.array.centre_local3(lens) + local);
                    const ArrayRay ray = m.array.microlens->towards_sensor(m.array, lens, h, h - q);
                    if (!ray.passed || !(ray.direction.z < 0))
                        continue;
                    const Vec3 s = ray.origin + ((m.sensor.z_mm - ray.origin.z) / ray.direction.z) * ray.direction;
                    const Vec3 from = m.array.to_local(ray.origin);
                    const Vec3 along = mul_transposed(m.array.pose.rotation, ray.direction);
                    const Vec3 cross = from - (from.z / along.z) * along;
                    const Vec3 entry = m.array.centre_mm(m.array.nearest(cross.x, cross.y));
                    const Vec3 centre = e + ((m.sensor.z_mm - e.z) / (entry.z - e.z)) * (entry - e);
                    const double distance = std::hypot(s.x - centre.x, s.y - centre.y);
                    if (std::isfinite(distance))
                        reach = std::max(reach, distance);
                }
            }
        }
    }
    const double step = 2 * grown / kReachCellGrid * (m.sensor.z_mm - e.z) / (c.z - e.z);
    return reach > 0 ? 1.05 * reach + step : 0;
}

// The traced reach of lens (0, 0) as it is; where lenses tilt, also of that lens tilted by the
// largest tilt towards 8 azimuths, at the smallest and the largest focal factor the errors give
// (each in a camera whose other lenses are ideal), the largest of them.
double traced_reach_mm(const PlenopticCamera& m)
{
    if (!refracting_shape(*m.array.microlens) || !m.lens)
        return 0;
    double reach = traced_reach_of_centre_lens(m);
    if (!(m.array.errors && m.array.errors->tilts()))
        return reach;
    const double deviation = m.array.errors->max_focal_deviation();
    const double focal = m.array.microlens->focal_length_mm(0);
    for (int a = 0; a < 8; ++a) {
        for (double factor : {1 - deviation, 1 + deviation}) {
            LensTableRow row;
            row.lens = LensIndex{0, 0};
            row.error.tilt_deg = m.array.errors->max_tilt_deg();
            row.error.tilt_azimuth_deg = 45.0 * a;
            row.error.focal_factor = factor;
            PlenopticCamera tilted = m;
            tilted.array.errors = LensErrors::tabled(std::vector<LensTableRow>{row}, std::string(), &focal, 1);
            reach = std::max(reach, traced_reach_of_centre_lens(tilted));
        }
    }
    return reach;
}

OverlapGeometry overlap_geometry(const PlenopticCamera& m)
{
    OverlapGeometry g{0, 0, 0, 0, 0, 0, 0};
    const double main_distance = effective_main_distance_mm(m);
    const double array_distance = effective_array_distance_mm(m);
    g.magnification = array_distance / main_distance;
    if (m.pupil_bounds)
        g.disc_mm = m.pupil_bounds->reach_mm() * g.magnification;
    else if (m.lens)
        g.disc_mm = m.lens->exit_pupil_radius() * g.magnification;
    if (m.array.microlens->forms_image()) {
        // worst: the ideal lenses' defocus, which the warning speaks of; reach: with the errors'
        // focal lengths and a clear gap's unbent light too, which the modelling must cover.
        double worst = 0, reach = 0;
        const double deviation = m.array.errors ? m.array.errors->max_focal_deviation() : 0;
        for (int t = 0; t < m.array.lens_type_count; ++t) {
            const double f = m.array.microlens->focal_length_mm(t);
            worst = std::max(worst, std::fabs(1 + g.magnification - array_distance / f));
            for (double scale : {1 - deviation, 1 + deviation})
                reach = std::max(reach, std::fabs(1 + g.magnification - array_distance / (scale * f)));
        }
        reach = std::max(reach, worst);
        if (m.array.fill_factor < 1 && !m.array.mask)
            reach = std::max(reach, 1 + g.magnification);  // light through a clear gap is not bent
        g.blur_mm = m.array.cell_circumradius_mm * reach;
        g.blur_inradius_mm = m.array.cell_inradius_mm * worst;
        g.traced_mm = m.array.baffles ? 0 : traced_reach_mm(m);
        g.blur_mm = std::max(g.blur_mm, g.traced_mm - g.disc_mm);
    }
    // Displaced lenses move their microimages by up to this relative to their cells.
    if (m.array.errors)
        g.shift_mm = 2 * (m.array.errors->max_shift_mm() + m.array.errors->max_dz_mm()) * (1 + g.magnification);
    g.cell_mm = m.array.cell_inradius_mm * (1 + g.magnification);
    return g;
}

// The lens says where light from the array's plane (or the sensor's) passes it.
void place_pupil_bounds(PlenopticCamera& m)
{
    m.pupil_bounds = nullptr;
    m.lit_area = nullptr;
    if (!m.lens)
        return;
    m.pupil_bounds = m.lens->pupil_bounds(m.array.grid == GridType::None ? m.sensor.z_mm : m.array.pose.centre_mm.z);
    if (m.pupil_bounds && m.array.grid == GridType::None)
        m.lit_area = m.lens->lit_area(*m.pupil_bounds, m.sensor.irradiance_k_mm2, m.sensor.angular_exponent);
}

// Overlap: a bound at the array centre says whether a neighbour's light can reach a microimage
// cell at all, and how many rings of neighbours a pixel must consider.
Overlap overlap_of(const PlenopticCamera& m)
{
    Overlap overlap;
    if (m.array.grid == GridType::None || !m.lens || m.array.baffles)
        return overlap;
    const OverlapGeometry g = overlap_geometry(m);
    const double reach = g.disc_mm + g.blur_mm + g.shift_mm;
    if (!(reach > g.cell_mm))
        return overlap;
    overlap.modelled = true;
    if (g.traced_mm > 0)
        overlap.reach_mm = g.traced_mm + g.shift_mm;
    const double pixel_reach = 0.5 * std::hypot(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1]);
    const double lattice_reach = (reach + pixel_reach) / (1 + g.magnification) + m.array.cell_circumradius_mm;
    // Ring r of the lattice is at least r times this far from the own lens.
    const double ring_step = m.array.row_spacing_mm();
    const bool lenses_tilt = m.array.errors && m.array.errors->tilts();
    double rings = std::ceil(lattice_reach / ring_step) + (m.array.pose.tilted || lenses_tilt ? 1 : 0);
    if (!(rings >= 1))
        rings = 1;
    if (!(rings <= kMaxOverlapRings)) {
        rings = kMaxOverlapRings;
        overlap.rings_capped = true;
    }
    overlap.rings = int(rings);
    return overlap;
}

} // namespace

double effective_main_distance_mm(const PlenopticCamera& model)
{
    return model.lens ? model.lens->exit_pupil_centre().z - model.array.pose.centre_mm.z : 0.0;
}

double effective_array_distance_mm(const PlenopticCamera& model)
{
    return model.array.pose.centre_mm.z - model.sensor.z_mm;
}

PlenopticCamera with_film(PlenopticCamera model, int width, int height)
{
    model.sensor.film = Film{width, height};
    if (model.spectral) {
        std::shared_ptr<SpectralCameras> spectral = std::make_shared<SpectralCameras>(*model.spectral);
        for (PlenopticCamera& camera : spectral->cameras)
            camera.sensor.film = Film{width, height};
        model.spectral = spectral;
    }
    return model;
}

PlenopticCamera with_f_number(const PlenopticCamera& camera, double f_number)
{
    return with_film(make_camera(at_f_number(camera.spec, f_number)), camera.sensor.film.width, camera.sensor.film.height);
}

const Prescription& PlenopticCamera::prescription() const
{
    static const Prescription none = Prescription();
    const Prescription* own = lens ? lens->prescription() : nullptr;
    return own ? *own : none;
}

const ParaxialData& PlenopticCamera::paraxial() const
{
    static const ParaxialData none = ParaxialData();
    const ParaxialData* own = lens ? lens->paraxial() : nullptr;
    return own ? *own : none;
}

const std::string& PlenopticCamera::lens_file() const
{
    static const std::string none;
    return lens && lens->paraxial() ? spec.main.lens_file : none;
}

MetadataJson Sensor::metadata(double projected_solid_angle_sr, const SensorChainParams& chain,
                              const std::string& raw_file) const
{
    MetadataJson json = MetadataJson::object();
    json["pixel_size_mm"] = json_numbers(pixel_size_mm, 2);
    json["offset_mm"] = json_numbers(offset_mm, 2);
    json["plane_z_mm"] = json_number(z_mm);
    MetadataJson measures = MetadataJson::object();
    measures["model"] = radiometry_name(radiometry);
    measures["projected_solid_angle_sr"] = json_number_or_null(projected_solid_angle_sr > 0, projected_solid_angle_sr);
    measures["angular_response"] = json_number(angular_exponent);
    json["radiometry"] = measures;
    json["read_out"] = read_out_metadata(chain, raw_file);
    return json;
}

MetadataJson Sampling::metadata() const
{
    MetadataJson json = MetadataJson::object();
    json["adaptive"] = adaptive;
    json["min"] = samples_min;
    json["max"] = samples_max;
    json["confidence"] = json_number(confidence);
    json["variance"] = json_number(variance);
    return json;
}

PlenopticCamera make_camera(const CameraParams& params)
{
    PlenopticCamera m = PlenopticCamera();
    m.spec = params;
    m.mm_per_unit = params.mm_per_unit;
    m.sensor.radiometry = params.radiometry;
    m.sensor.irradiance_k_mm2 = 0;  // set once the geometry is known, below
    m.sensor.angular_exponent = params.sensor.angular_exponent;

    const MainLensParams& main = params.main;
    m.distance_mm = main.given ? main_lens_distance_mm(main, params.mm_per_unit) : 0;
    // A real lens's pupils and f-number are those of the aperture that limits the axial beam to the
    // array (or sensor), D behind it.
    m.lens = make_main_lens(main, m.distance_mm);
    m.has_focus_distance = m.lens && main.has_focus_distance && m.lens->forms_image();
    m.focus_distance_units = m.has_focus_distance ? main.focus_distance_units : 0;

    const double array_z = m.lens ? -m.distance_mm : 0.0;
    m.array = make_microlens_array(params.array, array_z);

    if (m.array.grid == GridType::None)
        m.sensor.z_mm = -m.distance_mm;
    else
        m.sensor.z_mm = array_z - m.array.distance_mm;

    m.sensor.irradiance_k_mm2 = irradiance_constant_mm2(m);

    place_pupil_bounds(m);

    for (int a = 0; a < 2; ++a) {
        m.sensor.pixel_size_mm[a] = params.sensor.pixel_size_mm[a];
        m.sensor.offset_mm[a] = params.sensor.offset_mm[a];
    }

    m.overlap = overlap_of(m);

    const SamplingParams& sampling = params.sampling;
    m.sampling.adaptive = sampling.adaptive;
    const int fixed_count = sampling.samples == kSamplesOmitted ? default_samples(params) : sampling.samples;
    m.sampling.samples_min = sampling.adaptive ? sampling.samples_min : fixed_count;
    m.sampling.samples_max = sampling.adaptive ? sampling.samples_max : fixed_count;
    m.sampling.confidence = sampling.confidence;
    m.sampling.variance = sampling.variance;
    if (m.sampling.adaptive)
        m.sampling.thresholds = adaptive_thresholds(m.sampling.samples_max, m.sampling.confidence, m.sampling.variance);
    m.sampling.aim = camera_can_aim(m);
    // Behind a traced lens, bounds with tight discs to aim by (the spectral bands' cameras, made
    // below at their wavelengths, aim by the bounds' own discs).
    if (m.sampling.aim && m.pupil_bounds && m.array.grid != GridType::None && !params.spectral.given())
        m.pupil_bounds = m.lens->pupil_bounds(m.array.pose.centre_mm.z, true);

    if (params.spectral.given()) {
        std::shared_ptr<SpectralCameras> spectral = std::make_shared<SpectralCameras>();
        spectral->bands = spectral_bands(params.spectral);
        for (const SpectralBand& band : spectral->bands)
            spectral->cameras.push_back(at_wavelength(m, band.wavelength_nm));
        m.spectral = spectral;
    }
    return m;
}

PlenopticCamera at_wavelength(const PlenopticCamera& camera, double wavelength_nm)
{
    PlenopticCamera m = camera;
    m.spectral = nullptr;
    m.array = camera.array.at_wavelength(wavelength_nm);
    std::shared_ptr<const MainLens> lens = camera.lens ? camera.lens->at_wavelength(wavelength_nm) : nullptr;
    if (lens) {
        m.lens = lens;
        place_pupil_bounds(m);
    }
    // The overlap bound of this lens and array, and never fewer rings than the d line's.
    const Overlap own = overlap_of(m);
    m.overlap.modelled = own.modelled || camera.overlap.modelled;
    m.overlap.rings = std::max(own.rings, camera.overlap.rings);
    m.overlap.rings_capped = own.rings_capped || camera.overlap.rings_capped;
    m.overlap.reach_mm = std::max(own.reach_mm, camera.overlap.reach_mm);
    return m;
}

std::string limiting_aperture_warning(const PlenopticCamera& m)
{
    if (!m.lens || !m.lens->paraxial() || !m.paraxial().valid || m.paraxial().aperture_surface < 0)
        return "";
    const std::vector<LensSurface>& rows = m.prescription().surfaces;
    const LensSurface& limiting = rows[size_t(m.paraxial().aperture_surface)];
    if (limiting.stop)
        return "";
    int stop = 0;
    while (!rows[size_t(stop)].stop)
        ++stop;
    return describe_surface(m.prescription(), stop, m.lens_file()) + " is written " + format_number(m.paraxial().stop_mm) +
           " mm wide, wider than the lens can use: " +
           describe_surface(m.prescription(), m.paraxial().aperture_surface, m.lens_file()) + ", clear aperture " +
           format_number(limiting.aperture_mm) + " mm, limits the axial beam, so the lens works at f/" +
           format_rounded(m.paraxial().f_number, true) + " (the stop alone would give f/" +
           format_rounded(f_number_for_stop_diameter(m.prescription(), m.paraxial().stop_mm), true) +
           "); the pupils, f-numbers and microimage diameter in the metadata are those of that surface. A stop of at "
           "most " + format_rounded(m.paraxial().largest_stop_mm, false) + " mm (f_number " +
           format_rounded(f_number_for_stop_diameter(m.prescription(), m.paraxial().largest_stop_mm), true) +
           " or slower) limits the beam itself";
}

std::vector<std::string> warnings(const PlenopticCamera& m)
{
    std::vector<std::string> out;
    const std::string aperture = limiting_aperture_warning(m);
    if (!aperture.empty())
        out.push_back(aperture);
    if (m.array.grid == GridType::None)
        return out;

    const double magnification = m.lens ? effective_array_distance_mm(m) / effective_main_distance_mm(m) : 0.0;
    const double spacing_mm = m.array.pitch_mm * (1 + magnification);
    const double spacing_px = spacing_mm / std::max(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1]);
    if (spacing_px < 2)
        out.push_back("microimages are only " + format_number(spacing_px) +
                      " pixels apart (lens pitch " + format_number(m.array.pitch_mm) + " mm, pixel size " +
                      format_number(std::max(m.sensor.pixel_size_mm[0], m.sensor.pixel_size_mm[1])) +
                      " mm): fewer than two pixels across leaves almost no angular resolution");

    if (m.lens) {
        const OverlapGeometry g = overlap_geometry(m);
        // Warn about overlap a round microlens of diameter p would show too; the small spill
        // through the cell corners of f-number-matched arrays is modelled without a warning.
        if (g.disc_mm + g.blur_inradius_mm > g.cell_mm * (1 + 1e-9)) {
            std::string message = "microimages overlap: light through one microlens reaches up to " +
                                  format_number(g.disc_mm + g.blur_mm) + " mm from its microimage centre, "
                                  "beyond its microimage cell (inradius " + format_number(g.cell_mm) +
                                  " mm); the light of neighbouring lenses is added where they meet";
            message += m.lens->overlap_advice(g.cell_mm - g.blur_inradius_mm, g.magnification);
            out.push_back(message);
        }
    }
    if (m.overlap.rings_capped)
        out.push_back("microimages overlap by more than " + std::to_string(kMaxOverlapRings) +
                      " rings of neighbouring lenses; light through lenses further away is ignored");
    return out;
}

} // namespace plenoptic
