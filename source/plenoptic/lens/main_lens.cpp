// SPDX-License-Identifier: AGPL-3.0-or-later
// The pinhole and the ideal thin lens behind the MainLens interface.

#include "plenoptic/lens/main_lens.h"

#include <algorithm>
#include <cmath>

#include "plenoptic/core/format.h"
#include "plenoptic/core/json.h"
#include "plenoptic/lens/lit_area.h"
#include "plenoptic/lens/pupil_bounds.h"
#include "plenoptic/core/sampling.h"

namespace plenoptic {

namespace {

// Whether (x, y) lies in the disc of this radius about the origin: squares where they cannot
// overflow (cheaper than hypot: this runs for every ray), hypot for absurdly large apertures.
bool inside_disc(double x, double y, double radius)
{
    if (radius < 1e150)
        return x * x + y * y <= radius * radius;  // an overflowing x * x is +inf: outside, as it should be
    return std::hypot(x, y) <= radius;
}

// The lens of a prescription at a wavelength (MainLens::at_wavelength): nullptr when no medium of it
// disperses.
std::shared_ptr<const MainLens> prescription_at(const Prescription& lens, double wavelength_nm, bool exact,
                                                double image_distance_mm)
{
    if (!dispersive(lens))
        return nullptr;
    return make_prescription_lens(prescription_at_wavelength(lens, wavelength_nm), 0, exact, image_distance_mm);
}

// Whether the line from `origin` along `direction` passes through the origin, heading towards it
// (to rounding).
bool through_origin(Vec3 origin, Vec3 direction)
{
    const Vec3 to_pinhole = -origin;
    const Vec3 c = cross(to_pinhole, direction);
    return !(dot(c, c) > 1e-24 * dot(to_pinhole, to_pinhole) * dot(direction, direction)) &&
           dot(to_pinhole, direction) > 0;
}

// A real lens's members of the main_lens section: its surfaces as the render used them (the stop at
// its working diameter, object side first), and its first-order data in the optics frame (z from
// the rear vertex towards the scene, mm).
void add_prescription_metadata(MetadataJson& section, const Prescription& lens, const ParaxialData& p,
                               const LensPlacement& placement)
{
    MetadataJson surfaces = MetadataJson::array();
    for (const LensSurface& s : lens.surfaces) {
        MetadataJson row = MetadataJson::object();
        row["stop"] = s.stop;
        row["radius_mm"] = json_number(s.radius_mm);
        row["thickness_mm"] = json_number(s.thickness_mm);
        row["ior"] = json_number(s.ior);
        row["aperture_mm"] = json_number(s.aperture_mm);
        // A dispersing medium's glass (absent for one that does not disperse).
        if (s.glass.abbe != 0)
            row["abbe_number"] = json_number(s.glass.abbe);
        if (s.glass.sellmeier) {
            MetadataJson sellmeier = MetadataJson::object();
            MetadataJson b = MetadataJson::array(), c = MetadataJson::array();
            for (int i = 0; i < 3; ++i) {
                b.push_back(json_number(s.glass.sellmeier_b[i]));
                c.push_back(json_number(s.glass.sellmeier_c_um2[i]));
            }
            sellmeier["b"] = b;
            sellmeier["c_um2"] = c;
            row["sellmeier"] = sellmeier;
        }
        // A conic or aspheric surface's terms (absent for a sphere or a plane).
        if (s.conic != 0)
            row["conic"] = json_number(s.conic);
        bool terms = false;
        for (int j = 0; j < s.aspheric_count; ++j)
            terms = terms || s.aspheric[j] != 0;
        if (terms) {
            MetadataJson aspheric = MetadataJson::array();
            for (int j = 0; j < s.aspheric_count; ++j)
                aspheric.push_back(json_number(s.aspheric[j]));
            row["aspheric"] = aspheric;
        }
        surfaces.push_back(row);
    }
    MetadataJson prescription = MetadataJson::object();
    prescription["lens_file"] = placement.lens_file.empty() ? MetadataJson(nullptr) : MetadataJson(placement.lens_file);
    prescription["blades"] = lens.blades;
    prescription["blade_rotation_deg"] = json_number(lens.blade_rotation_deg);
    prescription["surfaces"] = surfaces;
    section["prescription"] = prescription;

    const double length = p.valid ? p.rear_vertex_z : 0.0;
    const double exit_pupil_z = length - p.exit_pupil_z;
    MetadataJson paraxial = MetadataJson::object();
    paraxial["effective_focal_length_mm"] = json_number(p.efl_mm);
    paraxial["back_focal_distance_mm"] = json_number(p.bfd_mm);
    paraxial["front_focal_distance_mm"] = json_number(p.ffd_mm);
    paraxial["length_mm"] = json_number(length);
    paraxial["front_vertex_z_mm"] = json_number(length);
    paraxial["front_principal_plane_z_mm"] = json_number(length - p.front_principal_z);
    paraxial["rear_principal_plane_z_mm"] = json_number(length - p.rear_principal_z);
    paraxial["entrance_pupil_z_mm"] = json_number(length - p.entrance_pupil_z);
    paraxial["entrance_pupil_diameter_mm"] = json_number(p.entrance_pupil_mm);
    paraxial["exit_pupil_z_mm"] = json_number(exit_pupil_z);
    paraxial["exit_pupil_diameter_mm"] = json_number(p.exit_pupil_mm);
    paraxial["f_number"] = json_number(p.f_number);
    // Image side, as f-number matching needs it: exit pupil to the array (or sensor) over its diameter.
    paraxial["working_f_number"] = json_number((exit_pupil_z + placement.distance_mm) / p.exit_pupil_mm);
    // The aperture the pupils image (index into prescription.surfaces: the stop's, unless a rim
    // limits the axial beam), and the widest stop that still limits it (null: no rim ever does).
    paraxial["limiting_surface"] = p.aperture_surface;
    paraxial["largest_stop_diameter_mm"] = json_number(p.largest_stop_mm);
    // A dispersing lens's focus at the F, d and C lines (infinity focus), and its longitudinal colour.
    const ChromaticFocus colour = chromatic_focus(lens);
    if (colour.valid) {
        MetadataJson lines = MetadataJson::object();
        for (const LineFocus& line : colour.lines) {
            MetadataJson at = MetadataJson::object();
            at["wavelength_nm"] = json_number(line.wavelength_nm);
            at["effective_focal_length_mm"] = json_number(line.efl_mm);
            at["back_focal_distance_mm"] = json_number(line.bfd_mm);
            lines[line.line] = at;
        }
        paraxial["lines"] = lines;
        paraxial["longitudinal_colour_mm"] = json_number(colour.longitudinal_colour_mm);
    }
    section["paraxial"] = paraxial;
}

// Every ray through it passes through the origin.
class PinholeMainLens : public MainLens {
public:
    const char* kind_name() const override { return "pinhole"; }
    const char* chief_ray_description() const override { return "through the lens centre"; }
    bool forms_image() const override { return false; }
    Vec3 exit_pupil_centre() const override { return Vec3{0, 0, 0}; }
    double exit_pupil_radius() const override { return 0; }
    Vec3 exit_pupil_point(double, double) const override { return Vec3{0, 0, 0}; }
    // Only the line through the pinhole passes: the caller aims at it (exit_pupil_point).
    SceneRay to_scene(Vec3 origin, Vec3 direction, bool) const override
    {
        if (!through_origin(origin, direction))
            return SceneRay{origin, direction, false};
        return scene_ray(Vec3{0, 0, 0}, direction);
    }
    ImageRay to_image(Vec3 origin, Vec3 direction, bool) const override
    {
        if (!through_origin(origin, direction))
            return ImageRay{origin, direction, false};
        return image_ray(Vec3{0, 0, 0}, direction);
    }
    HomogeneousPoint paraxial_image(Vec3 point) const override { return HomogeneousPoint{point, 1}; }
};

// Ideal thin lens of focal length F in the plane z = 0, aperture disc of diameter A: a ray meeting
// the plane at m with direction w (unit z component) leaves with w' = w - m / F.
//
// With distortion (lens/distortion.h), the image-side ray through m is bent about m so that
// where the ideal lens's ray would cross the plane z = plane_z (the array, or the sensor) at
// normalised point u = (x, y) / -plane_z, the real ray crosses it at distort(u): every ray stays
// straight on both sides, and the object side is the ideal lens's.
class ThinMainLens : public MainLens {
public:
    ThinMainLens(double focal_length_mm, double aperture_mm, double f_number)
        : focal_(focal_length_mm), aperture_(aperture_mm), f_number_(f_number), radius_(0.5 * aperture_mm),
          given_distortion_(false), distorted_(false), distortion_(DistortionParams{{0, 0, 0}, {0, 0}}), plane_z_(0) {}
    ThinMainLens(double focal_length_mm, double aperture_mm, double f_number, const DistortionParams& distortion,
                 double plane_z)
        : focal_(focal_length_mm), aperture_(aperture_mm), f_number_(f_number), radius_(0.5 * aperture_mm),
          given_distortion_(true), distorted_(!is_identity(distortion) && plane_z < 0), distortion_(distortion),
          plane_z_(plane_z) {}
    const char* kind_name() const override { return "thin_lens"; }
    const DistortionParams* distortion() const override { return given_distortion_ ? &distortion_ : nullptr; }
    void add_metadata(MetadataJson& section, const LensPlacement& placement) const override
    {
        if (!given_distortion_)
            return;
        // Radial-tangential polynomial on the plane z = -D, coordinates (x, y) / D.
        MetadataJson distortion = MetadataJson::object();
        distortion["radial"] = json_numbers(distortion_.radial, 3);
        distortion["tangential"] = json_numbers(distortion_.tangential, 2);
        distortion["plane_z_mm"] = json_number(-placement.distance_mm);
        section["distortion"] = distortion;
    }
    const char* chief_ray_description() const override { return "through the lens centre"; }
    double focal_length_mm() const override { return focal_; }
    double aperture_mm() const override { return aperture_; }
    double f_number() const override { return f_number_; }
    bool front_window(FrontWindow* window) const override
    {
        *window = FrontWindow{0, radius_, 0};
        return aperture_ > 0;
    }
    FrontWindow entrance_pupil() const override { return FrontWindow{0, radius_, 0}; }
    std::string dark_image_advice(double distance_mm) const override
    {
        return " (main-lens aperture " + format_number(aperture_) + " mm, f-number " + format_number(f_number_) +
               "; main lens to array or sensor " + format_number(distance_mm) +
               " mm: a focus distance at the focal length puts it far behind the lens)";
    }
    std::string overlap_advice(double free_mm, double magnification) const override
    {
        if (!(free_mm > 0))
            return "";
        return "; a main-lens f_number of at least " + format_number(focal_ / (2 * free_mm / magnification)) +
               " avoids it";
    }
    Vec3 exit_pupil_centre() const override { return Vec3{0, 0, 0}; }
    double exit_pupil_radius() const override { return radius_; }
    Vec3 exit_pupil_point(double u, double v) const override
    {
        const Vec2 disc = concentric_disc(u, v);
        return Vec3{radius_ * disc.x, radius_ * disc.y, 0};
    }
    SceneRay to_scene(Vec3 origin, Vec3 direction, bool check_apertures) const override
    {
        if (!(direction.z > 0) || !(origin.z < 0))
            return SceneRay{origin, direction, false};
        const double travel = -origin.z / direction.z;
        const double mx = origin.x + travel * direction.x;
        const double my = origin.y + travel * direction.y;
        if (check_apertures && !inside_disc(mx, my, radius_))
            return SceneRay{Vec3{mx, my, 0}, direction, false};  // misses the aperture: carries no light
        double sx = direction.x / direction.z, sy = direction.y / direction.z;  // slopes per unit of z
        if (distorted_) {
            // The real ray crosses the plane at h; the ideal ray through m crosses it at h_u.
            const double scale = -plane_z_;
            const Vec2 h{mx - scale * sx, my - scale * sy};
            Vec2 ideal;
            if (!undistort(distortion_, Vec2{h.x / scale, h.y / scale}, &ideal))
                return SceneRay{Vec3{mx, my, 0}, direction, false};  // beyond the distortion's reach
            sx = (mx - scale * ideal.x) / scale;
            sy = (my - scale * ideal.y) / scale;
        }
        const double wx = sx - mx / focal_;
        const double wy = sy - my / focal_;
        return scene_ray(Vec3{mx, my, 0}, Vec3{wx, wy, 1});
    }
    // The reverse of to_scene: arriving with slope a = direction / |direction.z| at m, the ray
    // leaves with a - m / F (to_scene's rule read backwards).
    ImageRay to_image(Vec3 origin, Vec3 direction, bool check_apertures) const override
    {
        if (!(direction.z < 0) || !(origin.z > 0))
            return ImageRay{origin, direction, false};
        const double travel = -origin.z / direction.z;
        const double mx = origin.x + travel * direction.x;
        const double my = origin.y + travel * direction.y;
        if (check_apertures && !inside_disc(mx, my, radius_))
            return ImageRay{Vec3{mx, my, 0}, direction, false};
        double ax = direction.x / -direction.z - mx / focal_;
        double ay = direction.y / -direction.z - my / focal_;
        if (distorted_) {
            const double scale = -plane_z_;
            const Vec2 real = distort(distortion_, Vec2{(mx + scale * ax) / scale, (my + scale * ay) / scale});
            ax = (scale * real.x - mx) / scale;
            ay = (scale * real.y - my) / scale;
        }
        return image_ray(Vec3{mx, my, 0}, Vec3{ax, ay, -1});
    }
    // X' = X / (1 - z / F), written homogeneously (the ideal image: distortion moves it).
    HomogeneousPoint paraxial_image(Vec3 point) const override { return HomogeneousPoint{point, 1 - point.z / focal_}; }

private:
    double focal_;
    double aperture_;
    double f_number_;
    double radius_;
    bool given_distortion_;  // made with a distortion (even one that moves nothing)
    bool distorted_;
    DistortionParams distortion_;
    double plane_z_;
};

// The paraxial equivalent of a prescription: principal planes at z = front_h and z = rear_h
// (optics frame, +z towards the scene, so front_h > rear_h for an ordinary lens), effective focal
// length F, exit pupil of radius r at z = pupil_z. A ray from the image side meets the rear
// principal plane at m, is refracted there as by a thin lens (w' = w - m / F) and continues from
// the same height on the front principal plane; it passes when it crosses the exit pupil's plane
// inside the pupil.
class ThickMainLens : public MainLens {
public:
    ThickMainLens(const Prescription& lens, const ParaxialData& p, double image_distance_mm)
        : lens_(lens), paraxial_(p), image_distance_mm_(image_distance_mm), length_(p.rear_vertex_z), focal_(p.efl_mm),
          front_h_(length_ - p.front_principal_z), rear_h_(length_ - p.rear_principal_z),
          pupil_z_(length_ - p.exit_pupil_z), radius_(0.5 * p.exit_pupil_mm) {}
    const char* kind_name() const override { return "thick_lens"; }
    const char* chief_ray_description() const override
    {
        return "through the centre of the entrance pupil (paraxial model)";
    }
    double focal_length_mm() const override { return paraxial_.efl_mm; }
    double aperture_mm() const override { return paraxial_.stop_mm; }
    double f_number() const override { return paraxial_.f_number; }
    const Prescription* prescription() const override { return &lens_; }
    const ParaxialData* paraxial() const override { return &paraxial_; }
    void add_metadata(MetadataJson& section, const LensPlacement& placement) const override
    {
        add_prescription_metadata(section, lens_, paraxial_, placement);
    }
    std::shared_ptr<const MainLens> at_wavelength(double wavelength_nm) const override
    {
        return prescription_at(lens_, wavelength_nm, false, image_distance_mm_);
    }
    double image_distance_mm() const { return image_distance_mm_; }
    bool front_window(FrontWindow* window) const override
    {
        *window = entrance_pupil();
        return paraxial_.valid;
    }
    FrontWindow entrance_pupil() const override
    {
        return FrontWindow{length_ - paraxial_.entrance_pupil_z, 0.5 * paraxial_.entrance_pupil_mm, 0};
    }
    Vec3 exit_pupil_centre() const override { return Vec3{0, 0, pupil_z_}; }
    double exit_pupil_radius() const override { return radius_; }
    Vec3 exit_pupil_point(double u, double v) const override
    {
        const Vec2 disc = concentric_disc(u, v);
        return Vec3{radius_ * disc.x, radius_ * disc.y, pupil_z_};
    }
    SceneRay to_scene(Vec3 origin, Vec3 direction, bool check_apertures) const override
    {
        if (!(direction.z > 0) || !(origin.z < rear_h_))
            return SceneRay{origin, direction, false};
        if (check_apertures) {
            const double to_pupil = (pupil_z_ - origin.z) / direction.z;
            const double px = origin.x + to_pupil * direction.x, py = origin.y + to_pupil * direction.y;
            if (!inside_disc(px, py, radius_))
                return SceneRay{Vec3{px, py, pupil_z_}, direction, false};
        }
        const double travel = (rear_h_ - origin.z) / direction.z;
        const double mx = origin.x + travel * direction.x;
        const double my = origin.y + travel * direction.y;
        const double wx = direction.x / direction.z - mx / focal_;
        const double wy = direction.y / direction.z - my / focal_;
        return scene_ray(Vec3{mx, my, front_h_}, Vec3{wx, wy, 1});
    }
    // The reverse: met at height m on the front principal plane, the ray leaves the rear one at
    // the same height with slope a - m / F, and passes when its line crosses the exit pupil.
    ImageRay to_image(Vec3 origin, Vec3 direction, bool check_apertures) const override
    {
        if (!(direction.z < 0) || !(origin.z > front_h_))
            return ImageRay{origin, direction, false};
        const double travel = (front_h_ - origin.z) / direction.z;
        const double mx = origin.x + travel * direction.x;
        const double my = origin.y + travel * direction.y;
        const double ax = direction.x / -direction.z - mx / focal_;
        const double ay = direction.y / -direction.z - my / focal_;
        if (check_apertures) {
            const double to_pupil = rear_h_ - pupil_z_;  // along the outgoing line, per unit of -z
            if (!inside_disc(mx + to_pupil * ax, my + to_pupil * ay, radius_))
                return ImageRay{Vec3{mx, my, rear_h_}, direction, false};
        }
        return image_ray(Vec3{mx, my, rear_h_}, Vec3{ax, ay, -1});
    }
    // The thin-lens conjugate about the principal planes: X - H maps to (X - H) / (1 - s / F)
    // about H', s the distance of X in front of H.
    HomogeneousPoint paraxial_image(Vec3 point) const override
    {
        const double s = point.z - front_h_;
        const double w = 1 - s / focal_;
        return HomogeneousPoint{Vec3{point.x, point.y, s + w * rear_h_}, w};
    }

private:
    Prescription lens_;
    ParaxialData paraxial_;
    double image_distance_mm_;  // where the axial beam the pupils belong to converges (NaN: the stop's)
    double length_;  // front vertex at z = length_, rear vertex at 0
    double focal_, front_h_, rear_h_, pupil_z_, radius_;
};

// The real lens, traced surface by surface. Lens frame (z from the front vertex towards the
// image) to optics frame: z_optics = length - z_lens, x and y unchanged (a mirror image, which
// a lens of revolution does not notice; the iris is turned with it).
class ExactMainLens : public MainLens {
public:
    ExactMainLens(const Prescription& lens, double length, const ThickMainLens& paraxial, double image_distance_mm)
        : lens_(lens), unbounded_(unbounded(lens)), length_(length), paraxial_(paraxial),
          image_distance_mm_(image_distance_mm)
    {
    }
    std::shared_ptr<const PupilBounds> pupil_bounds(double plane_z, bool tight) const override
    {
        // The round stop holds the iris: bounds from the lens without blades hold the lens with them.
        Prescription round = *prescription();
        round.blades = 0;
        const std::shared_ptr<const MainLens> traced = make_prescription_lens(round, 0, true, image_distance_mm_);
        return std::make_shared<PupilBounds>(round, *traced, plane_z, tight);
    }
    std::shared_ptr<const LitAreaTable> lit_area(const PupilBounds& bounds, double irradiance_k_mm2,
                                                 double angular_exponent) const override
    {
        if (prescription()->blades != 0)
            return nullptr;  // a blade iris: the per-pixel probes measure it
        return std::make_shared<LitAreaTable>(*this, bounds, irradiance_k_mm2, angular_exponent);
    }
    const char* kind_name() const override { return "prescription"; }
    const char* chief_ray_description() const override { return "through the centre of the aperture stop (traced)"; }
    double focal_length_mm() const override { return paraxial_.focal_length_mm(); }
    double aperture_mm() const override { return paraxial_.aperture_mm(); }
    double f_number() const override { return paraxial_.f_number(); }
    bool traced() const override { return true; }
    const Prescription* prescription() const override { return paraxial_.prescription(); }
    const ParaxialData* paraxial() const override { return paraxial_.paraxial(); }
    void add_metadata(MetadataJson& section, const LensPlacement& placement) const override
    {
        paraxial_.add_metadata(section, placement);  // the same surfaces and first-order data
    }
    std::shared_ptr<const MainLens> at_wavelength(double wavelength_nm) const override
    {
        return prescription_at(*prescription(), wavelength_nm, true, image_distance_mm_);
    }
    // The first surface: its vertex plane, clear radius and sag.
    bool front_window(FrontWindow* window) const override
    {
        const Prescription& lens = *prescription();
        if (lens.surfaces.empty())
            return false;
        const LensSurface& first = lens.surfaces.front();
        const double r = 0.5 * first.aperture_mm, R = std::fabs(first.radius_mm);
        const double sag = (first.stop || R == 0) ? 0 : R - std::sqrt(std::max(0.0, R * R - r * r));
        *window = FrontWindow{length_, r, sag};
        return true;
    }
    FrontWindow entrance_pupil() const override { return paraxial_.entrance_pupil(); }
    Vec3 exit_pupil_centre() const override { return paraxial_.exit_pupil_centre(); }
    double exit_pupil_radius() const override { return paraxial_.exit_pupil_radius(); }
    Vec3 exit_pupil_point(double u, double v) const override { return paraxial_.exit_pupil_point(u, v); }
    SceneRay to_scene(Vec3 origin, Vec3 direction, bool check_apertures) const override
    {
        const Traced out = (check_apertures ? lens_ : unbounded_).trace_from_image(to_lens(origin, direction));
        if (out.result != TraceResult::Passed)
            return SceneRay{origin, direction, false};
        return scene_ray(point_to_optics(out.ray.origin), direction_to_optics(out.ray.dir));
    }
    ImageRay to_image(Vec3 origin, Vec3 direction, bool check_apertures) const override
    {
        const Traced out = (check_apertures ? lens_ : unbounded_).trace_from_object(to_lens(origin, direction));
        if (out.result != TraceResult::Passed)
            return ImageRay{origin, direction, false};
        return image_ray(point_to_optics(out.ray.origin), direction_to_optics(out.ray.dir));
    }
    HomogeneousPoint paraxial_image(Vec3 point) const override { return paraxial_.paraxial_image(point); }

private:
    // Optics frame <-> lens frame: z_lens = length - z_optics, x and y unchanged (directions flip z).
    LensRay to_lens(Vec3 origin, Vec3 direction) const
    {
        return LensRay{Vec3{origin.x, origin.y, length_ - origin.z}, normalized(Vec3{direction.x, direction.y, -direction.z})};
    }
    Vec3 point_to_optics(Vec3 p) const { return Vec3{p.x, p.y, length_ - p.z}; }
    static Vec3 direction_to_optics(Vec3 d) { return Vec3{d.x, d.y, -d.z}; }

    TracingLens lens_;
    // Chief rays and depth maps want a ray for every pixel: no clear aperture blocks.
    static Prescription unbounded(Prescription lens)
    {
        for (LensSurface& surface : lens.surfaces)
            surface.aperture_mm = INFINITY;
        lens.blades = 0;
        return lens;
    }
    TracingLens unbounded_;  // the same without clear apertures or iris
    double length_;
    ThickMainLens paraxial_;
    double image_distance_mm_;  // where the axial beam the pupils belong to converges (NaN: the stop's)
};

} // namespace

std::shared_ptr<const MainLens> make_prescription_lens(const Prescription& lens, double stop_mm, bool exact,
                                                       double image_distance_mm)
{
    Prescription sized = lens;
    if (stop_mm > 0)
        for (LensSurface& surface : sized.surfaces)
            if (surface.stop)
                surface.aperture_mm = stop_mm;
    const ParaxialData p = paraxial_data(sized, 0, image_distance_mm);
    if (!p.valid)
        return nullptr;
    const double length = p.rear_vertex_z;  // front vertex at z_optics = length, rear at 0
    const ThickMainLens thick(sized, p, image_distance_mm);
    if (!exact)
        return std::make_shared<ThickMainLens>(thick);
    return std::make_shared<ExactMainLens>(sized, length, thick, image_distance_mm);
}

MetadataJson main_lens_metadata(const MainLens* lens, const LensPlacement& placement)
{
    const bool forms_image = lens && lens->forms_image();
    MetadataJson section = MetadataJson::object();
    section["type"] = lens ? lens->kind_name() : "none";
    section["focal_length_mm"] = json_number_or_null(forms_image, lens ? lens->focal_length_mm() : 0.0);
    section["aperture_mm"] = json_number_or_null(forms_image, lens ? lens->aperture_mm() : 0.0);
    section["f_number"] = json_number_or_null(forms_image, lens ? lens->f_number() : 0.0);
    section["distance_mm"] = json_number_or_null(lens != nullptr, placement.distance_mm);
    section["focus_distance"] = json_number_or_null(placement.has_focus_distance, placement.focus_distance_units);
    if (lens)
        lens->add_metadata(section, placement);
    return section;
}

std::shared_ptr<const MainLens> make_pinhole_lens() { return std::make_shared<PinholeMainLens>(); }

std::shared_ptr<const MainLens> make_thin_lens(double focal_length_mm, double aperture_mm, double f_number,
                                               const DistortionParams* distortion, double plane_z)
{
    if (distortion)
        return std::make_shared<ThinMainLens>(focal_length_mm, aperture_mm, f_number, *distortion, plane_z);
    return std::make_shared<ThinMainLens>(focal_length_mm, aperture_mm, f_number);
}

SceneRay scene_ray(Vec3 origin, Vec3 direction)
{
    const Vec3 unit = normalized(direction);
    const bool ok = is_finite(origin) && is_finite(unit) && unit.z > 0;
    return SceneRay{origin, unit, ok};
}

ImageRay image_ray(Vec3 origin, Vec3 direction)
{
    const Vec3 unit = normalized(direction);
    const bool ok = is_finite(origin) && is_finite(unit) && unit.z < 0;
    return ImageRay{origin, unit, ok};
}


} // namespace plenoptic
