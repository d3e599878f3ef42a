// SPDX-License-Identifier: AGPL-3.0-or-later
// Prescription lenses: reading, checking, paraxial data and the exact trace (see the header).

#include "plenoptic_prescription.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace plenoptic {

namespace {

const double kPi = 3.14159265358979323846;

std::string row_name(const LensSurface& s, int index)
{
    std::ostringstream out;
    out << (s.stop ? "the stop (surface " : "surface ") << index + 1 << (s.stop ? ")" : "");
    return out.str();
}

bool parse_number(const std::string& token, double* value)
{
    errno = 0;
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
        return false;
    *value = v;
    return true;
}

// 2x2 paraxial transfer matrix on (height y, reduced angle n u).
struct Mat2 {
    double a, b, c, d;  // [[a, b], [c, d]]
};

Mat2 operator*(const Mat2& x, const Mat2& y)
{
    return Mat2{x.a * y.a + x.b * y.c, x.a * y.b + x.b * y.d, x.c * y.a + x.d * y.c, x.c * y.b + x.d * y.d};
}

const Mat2 kIdentity{1, 0, 0, 1};
Mat2 refraction(double power) { return Mat2{1, 0, -power, 1}; }
Mat2 transfer(double thickness, double index) { return Mat2{1, thickness / index, 0, 1}; }

// Index of the medium after surface i (the stop keeps the medium before it).
double medium_after(const Prescription& lens, int i)
{
    double n = 1;
    for (int k = 0; k <= i; ++k)
        if (!lens.surfaces[k].stop)
            n = lens.surfaces[k].ior;
    return n;
}

double surface_power(const Prescription& lens, int i)
{
    const LensSurface& s = lens.surfaces[i];
    if (s.stop || s.radius_mm == 0)
        return 0;
    const double before = i == 0 ? 1.0 : medium_after(lens, i - 1);
    return (s.ior - before) / s.radius_mm;
}

// Matrix from just before surface `from` to just after surface `to` (inclusive), translations
// between them included.
Mat2 system_matrix(const Prescription& lens, int from, int to)
{
    Mat2 m = kIdentity;
    for (int i = from; i <= to; ++i) {
        if (i > from)
            m = transfer(lens.surfaces[i - 1].thickness_mm, medium_after(lens, i - 1)) * m;
        m = refraction(surface_power(lens, i)) * m;
    }
    return m;
}

int stop_index(const Prescription& lens)
{
    for (size_t i = 0; i < lens.surfaces.size(); ++i)
        if (lens.surfaces[i].stop)
            return int(i);
    return -1;
}

// Inside the stop's opening: the circle of the stop's diameter, or the iris polygon whose corners
// lie on that circle.
bool inside_stop(const Prescription& lens, const LensSurface& stop, double x, double y)
{
    const double r = 0.5 * stop.aperture_mm;
    if (x * x + y * y > r * r)
        return false;
    if (lens.blades < 3)
        return true;
    const double apothem = r * std::cos(kPi / lens.blades);
    const double rotation = lens.blade_rotation_deg * kPi / 180;
    for (int k = 0; k < lens.blades; ++k) {
        const double angle = rotation + 2 * kPi * k / lens.blades;
        if (x * std::cos(angle) + y * std::sin(angle) > apothem)
            return false;
    }
    return true;
}

// Refracts unit direction d at a surface with unit normal `normal` (either orientation) from
// index n1 into index n2. False on total internal reflection.
bool refract(Vec3 d, Vec3 normal, double n1, double n2, Vec3* out)
{
    Vec3 n = normal;
    double cos_i = -dot(n, d);
    if (cos_i < 0) {
        n = -n;
        cos_i = -cos_i;
    }
    const double eta = n1 / n2;
    const double k = 1 - eta * eta * (1 - cos_i * cos_i);
    if (k < 0)
        return false;
    *out = normalized(eta * d + (eta * cos_i - std::sqrt(k)) * n);
    return true;
}

// Meets surface i (vertex at z) with the ray; false when it misses the surface's sphere, or
// meets it only behind the ray's origin.
bool meet_surface(const LensSurface& s, double z, const LensRay& ray, Vec3* hit, Vec3* normal)
{
    if (s.stop || s.radius_mm == 0) {
        if (ray.dir.z == 0)
            return false;
        const double t = (z - ray.origin.z) / ray.dir.z;
        if (!(t > 0))
            return false;
        *hit = ray.origin + t * ray.dir;
        *normal = Vec3{0, 0, -1};
        return true;
    }
    const double R = s.radius_mm;
    const Vec3 centre{0, 0, z + R};
    const Vec3 oc = ray.origin - centre;
    const double b = dot(oc, ray.dir);
    const double c = dot(oc, oc) - R * R;
    const double disc = b * b - c;
    if (!(disc >= 0))
        return false;
    const double root = std::sqrt(disc);
    // Two roots -b -/+ root; the cap around the vertex is met first when the ray travels towards
    // the centre's side (dir.z > 0 with R > 0, or dir.z < 0 with R < 0), second otherwise.
    // (Computed as q / a and c / q to keep precision when the roots differ greatly.)
    const double q = b > 0 ? -b - root : -b + root;
    double t0 = q, t1 = q != 0 ? c / q : q;
    if (t0 > t1)
        std::swap(t0, t1);
    const bool nearer = (ray.dir.z > 0) == (R > 0);
    const double t = nearer ? t0 : t1;
    if (!(t > 0))
        return false;
    *hit = ray.origin + t * ray.dir;
    *normal = (1 / R) * (*hit - centre);
    return true;
}

// z[i]: vertex of surface i; before[i], after[i]: the indices on either side of it.
Traced trace(const Prescription& lens, const double* z, const double* before, const double* after, const LensRay& in,
             bool from_image)
{
    const int count = int(lens.surfaces.size());
    LensRay ray{in.origin, normalized(in.dir)};
    for (int step = 0; step < count; ++step) {
        const int i = from_image ? count - 1 - step : step;
        const LensSurface& s = lens.surfaces[i];
        Vec3 hit, normal;
        if (!meet_surface(s, z[i], ray, &hit, &normal))
            return Traced{TraceResult::Missed, ray, i};
        if (s.stop) {
            if (!inside_stop(lens, s, hit.x, hit.y))
                return Traced{TraceResult::Stop, LensRay{hit, ray.dir}, i};
            ray.origin = hit;
            continue;
        }
        const double r = 0.5 * s.aperture_mm;
        if (hit.x * hit.x + hit.y * hit.y > r * r)
            return Traced{TraceResult::ClearAperture, LensRay{hit, ray.dir}, i};
        Vec3 dir;
        if (!refract(ray.dir, normal, from_image ? after[i] : before[i], from_image ? before[i] : after[i], &dir))
            return Traced{TraceResult::TotalInternalReflection, LensRay{hit, ray.dir}, i};
        ray = LensRay{hit, dir};
    }
    return Traced{TraceResult::Passed, ray, -1};
}

} // namespace

ParsedPrescription parse_lens_file(const std::string& text)
{
    ParsedPrescription parsed = ParsedPrescription();
    std::istringstream lines(text);
    std::string line;
    int number = 0;
    while (std::getline(lines, line)) {
        ++number;
        const size_t hash = line.find('#');
        if (hash != std::string::npos)
            line.erase(hash);
        std::istringstream fields(line);
        std::vector<std::string> tokens;
        std::string token;
        while (fields >> token)
            tokens.push_back(token);
        if (tokens.empty())
            continue;
        if (tokens.size() != 4) {
            std::ostringstream msg;
            msg << "a lens file row has four numbers (radius, thickness, index of refraction, aperture "
                   "diameter, in mm); this one has "
                << tokens.size();
            parsed.error = PrescriptionError{msg.str(), number};
            return parsed;
        }
        double v[4];
        for (int k = 0; k < 4; ++k)
            if (!parse_number(tokens[k], &v[k])) {
                parsed.error = PrescriptionError{"'" + tokens[k] + "' is not a finite number", number};
                return parsed;
            }
        parsed.prescription.surfaces.push_back(LensSurface{v[0], v[1], v[2], v[3], v[0] == 0, number});
    }
    parsed.error = check_prescription(parsed.prescription);
    return parsed;
}

PrescriptionError check_prescription(const Prescription& lens)
{
    if (lens.surfaces.empty())
        return PrescriptionError{"a prescription needs at least one surface", 0};
    int stops = 0, first_stop = -1;
    for (size_t i = 0; i < lens.surfaces.size(); ++i) {
        const LensSurface& s = lens.surfaces[i];
        const std::string name = row_name(s, int(i));
        if (!std::isfinite(s.radius_mm) || !std::isfinite(s.thickness_mm) || !std::isfinite(s.ior) ||
            !std::isfinite(s.aperture_mm))
            return PrescriptionError{name + ": every number must be finite", s.line};
        if (!(s.aperture_mm > 0))
            return PrescriptionError{name + ": the aperture diameter must be > 0 mm", s.line};
        if (s.thickness_mm < 0)
            return PrescriptionError{name + ": the thickness must be >= 0 mm", s.line};
        if (s.stop) {
            if (++stops == 2) {
                std::ostringstream msg;
                msg << "two aperture stops (rows with radius 0): surfaces " << first_stop + 1 << " and " << i + 1
                    << "; a lens has exactly one";
                return PrescriptionError{msg.str(), s.line};
            }
            first_stop = int(i);
            const double before = i == 0 ? 1.0 : medium_after(lens, int(i) - 1);
            if (s.ior != 0 && s.ior != before)
                return PrescriptionError{name + ": the stop does not refract; its index must be 0 or that of the "
                                                "medium it stands in",
                                         s.line};
            continue;
        }
        if (!(s.ior >= 1))
            return PrescriptionError{name + ": the index of refraction must be >= 1", s.line};
        if (s.radius_mm != 0 && s.aperture_mm > 2 * std::fabs(s.radius_mm))
            return PrescriptionError{name + ": the aperture diameter exceeds the surface's sphere (diameter 2 |radius|)",
                                     s.line};
    }
    if (stops == 0)
        return PrescriptionError{"the prescription has no aperture stop (a row with radius 0)", 0};
    if (medium_after(lens, int(lens.surfaces.size()) - 1) != 1)
        return PrescriptionError{row_name(lens.surfaces.back(), int(lens.surfaces.size()) - 1) +
                                     ": the last surface must open into air (index 1), where the sensor is",
                                 lens.surfaces.back().line};
    return PrescriptionError{"", 0};
}

std::vector<double> vertex_positions(const Prescription& lens)
{
    std::vector<double> z(lens.surfaces.size());
    double at = 0;
    for (size_t i = 0; i < lens.surfaces.size(); ++i) {
        z[i] = at;
        at += lens.surfaces[i].thickness_mm;
    }
    return z;
}

ParaxialData paraxial_data(const Prescription& lens, double stop_mm)
{
    ParaxialData p;
    const int count = int(lens.surfaces.size());
    const int k = stop_index(lens);
    if (count == 0 || k < 0)
        return p;
    const std::vector<double> z = vertex_positions(lens);
    const Mat2 S = system_matrix(lens, 0, count - 1);
    if (S.c == 0)
        return p;  // afocal
    p.efl_mm = -1 / S.c;
    p.rear_vertex_z = z[count - 1];
    p.bfd_mm = S.a * p.efl_mm;
    p.ffd_mm = S.d * p.efl_mm;
    p.rear_focal_z = p.rear_vertex_z + p.bfd_mm;
    p.front_focal_z = -p.ffd_mm;
    p.rear_principal_z = p.rear_focal_z - p.efl_mm;
    p.front_principal_z = p.front_focal_z + p.efl_mm;
    p.stop_z = z[k];
    p.stop_mm = stop_mm > 0 ? stop_mm : lens.surfaces[k].aperture_mm;
    // Entrance pupil: the stop imaged by the surfaces in front of it, seen from object space.
    Mat2 F = kIdentity;
    if (k > 0)
        F = transfer(lens.surfaces[k - 1].thickness_mm, medium_after(lens, k - 1)) * system_matrix(lens, 0, k - 1);
    if (F.a == 0)
        return p;  // entrance pupil at infinity
    p.entrance_pupil_z = F.b / F.a;
    p.entrance_pupil_mm = p.stop_mm / std::fabs(F.a);
    // Exit pupil: the stop imaged by the surfaces behind it, seen from image space.
    Mat2 B = kIdentity;
    if (k < count - 1)
        B = system_matrix(lens, k + 1, count - 1) * transfer(lens.surfaces[k].thickness_mm, medium_after(lens, k));
    if (B.d == 0)
        return p;  // exit pupil at infinity
    const double s = -B.b / B.d;
    p.exit_pupil_z = p.rear_vertex_z + s;
    p.exit_pupil_mm = p.stop_mm * std::fabs(B.a + s * B.c);
    p.f_number = p.efl_mm / p.entrance_pupil_mm;
    p.valid = std::isfinite(p.efl_mm) && std::isfinite(p.entrance_pupil_z) && std::isfinite(p.exit_pupil_z);
    return p;
}

ImageDistance paraxial_image_distance(const Prescription& lens, double object_mm)
{
    const int count = int(lens.surfaces.size());
    if (count == 0)
        return ImageDistance{false, 0};
    const Mat2 S = system_matrix(lens, 0, count - 1);
    double s;
    if (std::isinf(object_mm))
        s = S.c == 0 ? INFINITY : -S.a / S.c;
    else {
        const double denominator = S.c * object_mm + S.d;
        s = denominator == 0 ? INFINITY : -(S.a * object_mm + S.b) / denominator;
    }
    return ImageDistance{std::isfinite(s) && s > 0, s};
}

TracingLens::TracingLens(const Prescription& lens)
    : lens_(lens), z_(vertex_positions(lens)), before_(lens.surfaces.size()), after_(lens.surfaces.size())
{
    double n = 1;
    for (size_t i = 0; i < lens.surfaces.size(); ++i) {
        before_[i] = n;
        if (!lens.surfaces[i].stop)
            n = lens.surfaces[i].ior;
        after_[i] = lens.surfaces[i].stop ? before_[i] : lens.surfaces[i].ior;
    }
}

Traced TracingLens::trace_from_image(const LensRay& in) const
{
    return trace(lens_, z_.data(), before_.data(), after_.data(), in, true);
}

Traced TracingLens::trace_from_object(const LensRay& in) const
{
    return trace(lens_, z_.data(), before_.data(), after_.data(), in, false);
}

Traced trace_from_image(const Prescription& lens, const LensRay& in) { return TracingLens(lens).trace_from_image(in); }
Traced trace_from_object(const Prescription& lens, const LensRay& in) { return TracingLens(lens).trace_from_object(in); }

double stop_diameter_for_f_number(const Prescription& lens, double f_number)
{
    const ParaxialData full = paraxial_data(lens);
    if (!full.valid || !(f_number > 0))
        return NAN;
    // The entrance pupil scales with the stop: EP = stop / |F.a|.
    const double ratio = full.entrance_pupil_mm / full.stop_mm;
    return full.efl_mm / f_number / ratio;
}

} // namespace plenoptic
