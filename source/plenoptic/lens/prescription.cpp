// SPDX-License-Identifier: AGPL-3.0-or-later
// Prescription lenses: reading, checking, paraxial data and the exact trace (see the header).

#include "plenoptic/lens/prescription.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>

namespace plenoptic {

// The spherical trace's helpers are inlined into both traces (spheres only, with aspheres): used
// twice, the compiler would call them, and a spherical render would pay for the calls.
#if defined(__GNUC__)
#define PLENOPTIC_TRACE_INLINE inline __attribute__((always_inline))
#else
#define PLENOPTIC_TRACE_INLINE inline
#endif

namespace {

std::string row_name(const LensSurface& s, int index)
{
    std::ostringstream out;
    out << (s.stop ? "the stop (surface " : "surface ") << index + 1 << (s.stop ? ")" : "");
    return out.str();
}

std::string mm(double value)
{
    std::ostringstream out;
    out << std::setprecision(6) << value << " mm";
    return out.str();
}

// row_name with the row's line: "surface 3 (line 7)", "the stop (surface 2, line 6)".
std::string row_at(const LensSurface& s, int index)
{
    const std::string line = s.line > 0 ? "line " + std::to_string(s.line) : std::string();
    if (s.stop)
        return "the stop (surface " + std::to_string(index + 1) + (line.empty() ? "" : ", " + line) + ")";
    return row_name(s, index) + (line.empty() ? "" : " (" + line + ")");
}

// How far a surface's sphere lies from its vertex plane at height h from the axis (+z towards
// the image), for h within its clear aperture: R - sign(R) sqrt(R^2 - h^2), written without
// cancellation. 0 for a flat surface and the stop.
double sag(const LensSurface& s, double h)
{
    if (s.stop || s.radius_mm == 0)
        return 0;
    const double R = s.radius_mm;
    const double root = std::sqrt(std::max(0.0, R * R - h * h));
    return h * h / (R + (R > 0 ? root : -root));
}

// Consecutive rows i and i + 1 cross when, somewhere within the smaller of their clear
// apertures, row i + 1 lies in front of row i (towards the object). Their axial gap
// thickness_i + sag_{i+1}(h) - sag_i(h) is monotonic in h^2 (each sag is, and the difference
// of two sags of one sign is, since d sag / d(h^2) = 1 / (2 sqrt(R^2 - h^2)) shrinks with |R|),
// so it is least at the axis or at the rim: if the rim's gap is negative, the crossing height is
// where the gap is 0, found by bisection.
//
// With a conic or aspheric surface the gap need not be monotonic: it is sampled at
// kCrossingSamples heights from the axis to the rim (with the real sag, surface_sag_mm), and the
// first negative sample's crossing height found by bisection from the sample before it.
const int kCrossingSamples = 4096;

std::string crossing(const Prescription& lens, int i)
{
    const LensSurface& a = lens.surfaces[i];
    const LensSurface& b = lens.surfaces[i + 1];
    const double rim = 0.5 * std::min(a.aperture_mm, b.aperture_mm);
    const bool real = a.is_aspheric() || b.is_aspheric();
    const auto gap = [&](double h) {
        return real ? a.thickness_mm + surface_sag_mm(b, h) - surface_sag_mm(a, h) : a.thickness_mm + sag(b, h) - sag(a, h);
    };
    const double tolerance = real ? 1e-9 + 1e-12 * (std::fabs(surface_sag_mm(a, rim)) + std::fabs(surface_sag_mm(b, rim)) +
                                                    a.thickness_mm)
                                  : 1e-9 + 1e-12 * (std::fabs(sag(a, rim)) + std::fabs(sag(b, rim)) + a.thickness_mm);
    double lo = 0, hi = rim, at_rim = gap(rim);  // at_rim: the gap where the crossing is reported
    if (real) {
        int k = 1;
        for (; k <= kCrossingSamples; ++k) {
            const double h = rim * k / kCrossingSamples;
            if (gap(h) < -tolerance)
                break;
        }
        if (k > kCrossingSamples)
            return "";
        lo = rim * (k - 1) / kCrossingSamples;
        hi = rim * k / kCrossingSamples;
        at_rim = gap(hi);
    } else if (!(at_rim < -tolerance)) {
        return "";
    }
    const double reported = hi;  // gap(lo) >= 0 > gap(hi)
    for (int k = 0; k < 200 && hi - lo > 1e-12 * rim; ++k) {
        const double mid = 0.5 * (lo + hi);
        (gap(mid) >= 0 ? lo : hi) = mid;
    }
    std::ostringstream msg;
    msg << row_at(a, i) << " and " << row_at(b, i + 1) << " cross inside their clear apertures: they meet "
        << mm(lo) << " from the axis, and at " << mm(reported) << " from it"
        << (reported == rim ? " (the smaller clear aperture's rim) " : " ")
        << row_name(b, i + 1) << " lies " << mm(-at_rim) << " in front of " << row_name(a, i)
        << "; consecutive surfaces may touch but not cross within their clear apertures (a larger thickness on "
        << row_name(a, i) << ", now " << mm(a.thickness_mm) << ", or smaller apertures)";
    return msg.str();
}

// A conic or aspheric surface's own refusals: a conic constant on a flat surface (which it would
// not change), a sag undefined (the conic's root not real) or not finite somewhere within the
// clear aperture.
std::string check_asphere(const LensSurface& s)
{
    const double rim = 0.5 * s.aperture_mm;
    std::ostringstream msg;
    msg << std::setprecision(6);
    if (s.radius_mm == 0 && s.conic != 0) {
        msg << "the conic constant " << s.conic
            << " is given on a flat surface (radius 0), which it does not change; a flat surface takes aspheric "
               "terms alone (a Schmidt plate's profile)";
        return msg.str();
    }
    if (s.radius_mm != 0) {
        // 1 - (1 + k) c^2 r^2 falls (k > -1) or rises (k <= -1) with r: its least is at the rim.
        const double c = 1 / s.radius_mm;
        if (!(1 - (1 + s.conic) * c * c * rim * rim >= 0)) {
            msg << "with the conic constant " << s.conic << " and radius " << mm(s.radius_mm)
                << " the sag is undefined beyond " << mm(std::fabs(s.radius_mm) / std::sqrt(1 + s.conic))
                << " from the axis (1 - (1 + k) r^2 / R^2 < 0), inside the clear aperture's rim at " << mm(rim)
                << " (a smaller aperture diameter, or a conic constant nearer -1)";
            return msg.str();
        }
    }
    // |a4 r^4 + ...| <= |a4| r^4 + ... , which grows with r: finite at the rim, finite everywhere.
    double bound = 0;
    for (int j = s.aspheric_count - 1; j >= 0; --j)
        bound = bound * rim * rim + std::fabs(s.aspheric[j]);
    bound *= rim * rim * rim * rim;
    if (!std::isfinite(bound) || !std::isfinite(surface_sag_mm(s, rim)) || bound > kPrescriptionMaxLengthMm) {
        msg << "the aspheric terms make the sag exceed " << mm(kPrescriptionMaxLengthMm)
            << " within the clear aperture (rim at " << mm(rim) << ")";
        return msg.str();
    }
    return "";
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
PLENOPTIC_TRACE_INLINE bool inside_stop(const Prescription& lens, const LensSurface& stop, double x, double y)
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
PLENOPTIC_TRACE_INLINE bool refract(Vec3 d, Vec3 normal, double n1, double n2, Vec3* out)
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
PLENOPTIC_TRACE_INLINE bool meet_surface(const LensSurface& s, double z, const LensRay& ray, Vec3* hit, Vec3* normal)
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

// d sag / d(r^2) at u = r^2 (surface_sag_mm's derivative): c / (2 sqrt(1 - (1 + k) c^2 u)) for the
// conic, plus 2 a4 u + 3 a6 u^2 + ...; NaN where the conic's root is not real.
double sag_slope_u(const LensSurface& s, double u)
{
    double slope = 0;
    if (s.radius_mm != 0) {
        const double c = 1 / s.radius_mm;
        const double q = 1 - (1 + s.conic) * c * c * u;
        if (!(q > 0))
            return NAN;
        slope = c / (2 * std::sqrt(q));
    }
    double poly = 0;
    for (int j = s.aspheric_count - 1; j >= 0; --j)
        poly = poly * u + (j + 2) * s.aspheric[j];
    return slope + poly * u;
}

// The ray parameter where a ray meets a surface's base conic (k and c, without the aspheric
// terms), vertex at z: the smallest t > 0 of (1 + k) c z'^2 - 2 z' + c r^2 = 0 (z' = z - vertex)
// on the sag's branch (1 - (1 + k) c z' >= 0); the vertex plane's t for a flat surface. NaN when
// the ray meets neither.
double meet_base_conic(const LensSurface& s, double z, const LensRay& ray)
{
    const Vec3 o{ray.origin.x, ray.origin.y, ray.origin.z - z};
    const Vec3& d = ray.dir;
    if (s.radius_mm == 0)
        return d.z != 0 && -o.z / d.z > 0 ? -o.z / d.z : NAN;
    const double c = 1 / s.radius_mm, p = (1 + s.conic) * c;
    const double A = c * (d.x * d.x + d.y * d.y) + p * d.z * d.z;
    const double B = 2 * (c * (o.x * d.x + o.y * d.y) - d.z + p * o.z * d.z);
    const double C = c * (o.x * o.x + o.y * o.y) - 2 * o.z + p * o.z * o.z;
    double roots[2];
    int n = 0;
    if (std::fabs(A) <= 1e-15 * (std::fabs(B) + std::fabs(C))) {
        if (B != 0)
            roots[n++] = -C / B;
    } else {
        const double disc = B * B - 4 * A * C;
        if (!(disc >= 0))
            return NAN;
        const double q = -0.5 * (B + (B >= 0 ? 1 : -1) * std::sqrt(disc));
        roots[n++] = q / A;
        if (q != 0)
            roots[n++] = C / q;
    }
    double best = NAN;
    for (int k = 0; k < n; ++k) {
        const double t = roots[k];
        if (!(t > 0) || !(1 - p * (o.z + t * d.z) >= 0))
            continue;
        if (!(best <= t))
            best = t;
    }
    return best;
}

} // namespace

const double kAsphereToleranceMm = 1e-9;
const int kAsphereIterations = 32;

bool meet_aspheric_surface(const LensSurface& s, double z, const LensRay& ray, Vec3* hit, Vec3* normal)
{
    // Newton's method on f(t) = z(t) - vertex - sag(r(t)^2) from the base conic's hit (or the vertex
    // plane's when the ray misses the conic), until a step moves less than kAsphereToleranceMm along
    // the (unit) ray.
    double t = meet_base_conic(s, z, ray);
    if (!std::isfinite(t)) {
        LensSurface plane;
        t = meet_base_conic(plane, z, ray);
        if (!std::isfinite(t))
            return false;
    }
    const Vec3& o = ray.origin;
    const Vec3& d = ray.dir;
    for (int k = 0; k < kAsphereIterations; ++k) {
        const double x = o.x + t * d.x, y = o.y + t * d.y, u = x * x + y * y;
        const double f = o.z + t * d.z - z - surface_sag_mm(s, std::sqrt(u));
        const double slope = sag_slope_u(s, u);
        const double df = d.z - slope * 2 * (x * d.x + y * d.y);
        if (!std::isfinite(f) || !std::isfinite(df) || df == 0)
            return false;
        const double step = f / df;
        t -= step;
        if (std::fabs(step) <= kAsphereToleranceMm) {
            if (!(t > 0))
                return false;
            *hit = o + t * d;
            const double g = sag_slope_u(s, hit->x * hit->x + hit->y * hit->y);
            if (!std::isfinite(g))
                return false;
            *normal = normalized(Vec3{-2 * g * hit->x, -2 * g * hit->y, 1});
            return true;
        }
    }
    return false;
}

namespace {

// z[i]: vertex of surface i; before[i], after[i]: the indices on either side of it. With
// kAspheric, a surface marked in aspheric[] is met by meet_aspheric_surface; without, every surface
// is a sphere or a plane (the lens has no asphere: the choice is made once per lens).
template <bool kAspheric>
PLENOPTIC_TRACE_INLINE Traced trace(const Prescription& lens, const double* z, const double* before, const double* after,
             const unsigned char* aspheric, const LensRay& in, bool from_image)
{
    const int count = int(lens.surfaces.size());
    LensRay ray{in.origin, normalized(in.dir)};
    for (int step = 0; step < count; ++step) {
        const int i = from_image ? count - 1 - step : step;
        const LensSurface& s = lens.surfaces[i];
        Vec3 hit, normal;
        if (kAspheric && aspheric[i]) {
            if (!meet_aspheric_surface(s, z[i], ray, &hit, &normal))
                return Traced{TraceResult::Missed, ray, i};
        } else if (!meet_surface(s, z[i], ray, &hit, &normal))
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

// axial_limit with the stop at diameter stop_mm. The paraxial marginal ray through the axial
// image point at z = rear vertex + D: in front of the lens it is (y0, u0) with
// (S.a + D S.c) y0 + (S.b + D S.d) u0 = 0 (height 0 on that plane); traced forward, its height at
// each surface's vertex. Heights scale with the ray, so the ratios of opening radius to height
// order the apertures whatever ray is taken.
AxialLimit axial_limit_sized(const Prescription& lens, double stop_mm, double image_distance_mm)
{
    AxialLimit limit;
    const int count = int(lens.surfaces.size());
    const int k = stop_index(lens);
    if (count == 0 || k < 0 || !std::isfinite(image_distance_mm))
        return limit;
    const Mat2 S = system_matrix(lens, 0, count - 1);
    const double D = image_distance_mm;
    const double y0 = S.b + D * S.d, u0 = -(S.a + D * S.c);
    double y = y0, nu = u0, n = 1;
    double stop_ratio = INFINITY, stop_height = 0, rim_ratio = INFINITY;
    for (int i = 0; i < count; ++i) {
        const LensSurface& s = lens.surfaces[i];
        if (i > 0)
            y += lens.surfaces[i - 1].thickness_mm * nu / n;
        const double radius = 0.5 * (s.stop ? stop_mm : s.aperture_mm);
        const double ratio = y != 0 ? radius / std::fabs(y) : INFINITY;
        if (s.stop) {
            stop_ratio = ratio;
            stop_height = std::fabs(y);
            continue;
        }
        if (ratio < rim_ratio) {
            rim_ratio = ratio;
            limit.rim = i;
        }
        if (s.radius_mm != 0)
            nu -= y * (s.ior - n) / s.radius_mm;
        n = s.ior;
    }
    if (!std::isfinite(y) || !std::isfinite(nu))
        return limit;
    limit.valid = true;
    limit.largest_stop_mm = limit.rim >= 0 ? 2 * stop_height * rim_ratio : INFINITY;
    limit.surface = limit.rim >= 0 && rim_ratio < stop_ratio * (1 - kApertureTolerance) ? limit.rim : k;
    return limit;
}

// The trace of a lens with a conic or aspheric surface, kept out of line so that the spherical
// trace inlines into TracingLens's functions as it did before aspheres existed.
#if defined(__GNUC__)
__attribute__((noinline))
#endif
Traced trace_aspheric(const Prescription& lens, const double* z, const double* before, const double* after,
                      const unsigned char* aspheric, const LensRay& in, bool from_image)
{
    return trace<true>(lens, z, before, after, aspheric, in, from_image);
}

} // namespace

double surface_sag_mm(const LensSurface& s, double r_mm)
{
    if (s.stop)
        return 0;
    const double u = r_mm * r_mm;
    double z = 0;
    if (s.radius_mm != 0) {
        const double c = 1 / s.radius_mm;
        const double q = 1 - (1 + s.conic) * c * c * u;
        if (!(q >= 0))
            return NAN;
        z = c * u / (1 + std::sqrt(q));
    }
    // a4 r^4 + a6 r^6 + ... by Horner's rule in u = r^2.
    double poly = 0;
    for (int j = s.aspheric_count - 1; j >= 0; --j)
        poly = poly * u + s.aspheric[j];
    return z + poly * u * u;
}

double flat_radius(double radius_mm)
{
    return std::fabs(radius_mm) > kPrescriptionMaxLengthMm ? 0.0 : radius_mm;
}

double reduced_blade_rotation(double degrees, int blades)
{
    if (!std::isfinite(degrees))
        return degrees;
    // fmod is exact; the second step's rounding is at most an ulp of 360 degrees.
    double turn = std::fmod(degrees, 360.0);
    if (turn < 0)
        turn += 360.0;
    if (blades >= 3) {
        const double period = 360.0 / blades;
        turn -= std::floor(turn / period) * period;
        if (!(turn >= 0 && turn < period))
            turn = 0;  // only a rounding at the period itself lands here
    } else if (turn >= 360.0) {
        turn = 0;  // -tiny + 360 rounds to 360
    }
    return turn;
}

ParsedPrescription parse_lens_file(const std::string& file_text)
{
    ParsedPrescription parsed = ParsedPrescription();
    // A UTF-8 byte-order mark (editors on Windows write one) is not part of the first row.
    const std::string bom = "\xEF\xBB\xBF";
    const std::string text = file_text.compare(0, bom.size(), bom) == 0 ? file_text.substr(bom.size()) : file_text;
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
        const size_t most = 6 + LensSurface::kMaxAspheric;
        if (tokens.size() < 4 || tokens.size() > most) {
            std::ostringstream msg;
            msg << "a lens file row has four numbers (radius, thickness, index of refraction, aperture "
                   "diameter, in mm) and optionally a fifth (the Abbe number V_d; 0: no dispersion), a sixth (the "
                   "conic constant) and up to eight more (the aspheric terms a4, a6, ..., a18); this one has "
                << tokens.size();
            parsed.error = PrescriptionError{msg.str(), number};
            return parsed;
        }
        double v[6 + LensSurface::kMaxAspheric] = {};
        for (size_t k = 0; k < tokens.size(); ++k)
            if (!parse_number(tokens[k], &v[k])) {
                parsed.error = PrescriptionError{"'" + tokens[k] + "' is not a finite number", number};
                return parsed;
            }
        const bool stop = v[0] == 0;
        Glass glass;
        glass.abbe = v[4];
        LensSurface surface{stop ? 0.0 : flat_radius(v[0]), v[1], v[2], v[3], stop, number, glass};
        surface.conic = v[5];
        surface.aspheric_count = tokens.size() > 6 ? int(tokens.size()) - 6 : 0;
        for (int j = 0; j < surface.aspheric_count; ++j)
            surface.aspheric[j] = v[6 + j];
        parsed.prescription.surfaces.push_back(surface);
    }
    if (parsed.prescription.surfaces.empty()) {
        const std::string what = file_text.empty()
            ? "the lens file is empty (0 bytes)"
            : "the lens file holds no surface row (only " +
                  std::string(text.find_first_not_of(" \t\r\n\f\v") == std::string::npos ? "blank lines" : "comments and blank lines") +
                  ")";
        parsed.error = PrescriptionError{what + "; a lens file has one row per surface, object side first, of four numbers "
                                                "(radius, thickness, index of refraction, aperture diameter, in mm)", 0};
        return parsed;
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
        const double bound = kPrescriptionMaxLengthMm;
        if (std::fabs(s.radius_mm) > bound)
            return PrescriptionError{name + ": the radius " + mm(s.radius_mm) + " lies beyond +-" + mm(bound) +
                                         " (a lens file or prescription { } reads such a radius as a flat surface, radius 0)",
                                     s.line};
        if (s.thickness_mm > bound)
            return PrescriptionError{name + ": the thickness " + mm(s.thickness_mm) + " exceeds " + mm(bound) +
                                         ", the bound of every length",
                                     s.line};
        if (s.aperture_mm > bound)
            return PrescriptionError{name + ": the aperture diameter " + mm(s.aperture_mm) + " exceeds " + mm(bound) +
                                         ", the bound of every length",
                                     s.line};
        if (!(s.aperture_mm > 0))
            return PrescriptionError{name + ": the aperture diameter must be > 0 mm", s.line};
        if (s.thickness_mm < 0)
            return PrescriptionError{name + ": the thickness must be >= 0 mm", s.line};
        if (!std::isfinite(s.conic))
            return PrescriptionError{name + ": the conic constant must be finite", s.line};
        if (s.aspheric_count < 0 || s.aspheric_count > LensSurface::kMaxAspheric)
            return PrescriptionError{name + ": a surface takes 1 to 8 aspheric terms (a4 to a18)", s.line};
        for (int j = 0; j < LensSurface::kMaxAspheric; ++j)
            if (!std::isfinite(s.aspheric[j]))
                return PrescriptionError{name + ": the aspheric term a" + std::to_string(2 * j + 4) + " must be finite",
                                         s.line};
        if (s.stop && s.is_aspheric())
            return PrescriptionError{name + ": the stop is a flat opening; it takes no conic constant or aspheric terms "
                                            "(0 in a lens file's sixth and later columns)",
                                     s.line};
        if (s.stop) {
            if (++stops == 2) {
                std::ostringstream msg;
                msg << "two aperture stops (rows with radius 0): surfaces " << first_stop + 1 << " and " << i + 1
                    << "; a lens has exactly one";
                return PrescriptionError{msg.str(), s.line};
            }
            first_stop = int(i);
            if (s.glass.dispersive())
                return PrescriptionError{name + ": the stop does not refract; it takes no Abbe number or Sellmeier "
                                                "coefficients (0 in a lens file's fifth column)",
                                         s.line};
            const double before = i == 0 ? 1.0 : medium_after(lens, int(i) - 1);
            if (s.ior != 0 && s.ior != before)
                return PrescriptionError{name + ": the stop does not refract; its index must be 0 or that of the "
                                                "medium it stands in",
                                         s.line};
            continue;
        }
        if (!(s.ior >= 1))
            return PrescriptionError{name + ": the index of refraction must be >= 1", s.line};
        if (s.glass.dispersive()) {
            if (s.ior == 1)
                return PrescriptionError{name + ": the medium after it is air (index 1), which does not disperse; it "
                                                "takes no Abbe number or Sellmeier coefficients (0 in a lens file's "
                                                "fifth column)",
                                         s.line};
            const std::string glass = check_glass(s.ior, s.glass);
            if (!glass.empty())
                return PrescriptionError{name + ": " + glass, s.line};
        }
        if (s.is_aspheric()) {
            const std::string message = check_asphere(s);
            if (!message.empty())
                return PrescriptionError{name + ": " + message, s.line};
        } else if (s.radius_mm != 0 && s.aperture_mm > 2 * std::fabs(s.radius_mm))
            return PrescriptionError{name + ": the aperture diameter exceeds the surface's sphere (diameter 2 |radius|)",
                                     s.line};
    }
    if (stops == 0)
        return PrescriptionError{"the prescription has no aperture stop (a row with radius 0)", 0};
    if (medium_after(lens, int(lens.surfaces.size()) - 1) != 1)
        return PrescriptionError{row_name(lens.surfaces.back(), int(lens.surfaces.size()) - 1) +
                                     ": the last surface must open into air (index 1), where the sensor is",
                                 lens.surfaces.back().line};
    for (size_t i = 0; i + 1 < lens.surfaces.size(); ++i) {
        const std::string message = crossing(lens, int(i));
        if (!message.empty())
            return PrescriptionError{message, lens.surfaces[i].line};
    }
    // The power, in one pass (system_matrix looks each medium up from the first surface).
    Mat2 S = kIdentity;
    double n = 1;
    for (size_t i = 0; i < lens.surfaces.size(); ++i) {
        const LensSurface& s = lens.surfaces[i];
        if (i > 0)
            S = transfer(lens.surfaces[i - 1].thickness_mm, n) * S;
        if (s.stop)
            continue;
        if (s.radius_mm != 0)
            S = refraction((s.ior - n) / s.radius_mm) * S;
        n = s.ior;
    }
    if (S.c > 0) {
        std::ostringstream msg;
        msg << "the lens has a negative focal length: its effective focal length is " << mm(-1 / S.c)
            << " (paraxial, from its surfaces), a diverging lens, or a system that forms an intermediate image "
               "(a relay); the camera's f-number, pupils, focus and metadata need a main lens with a positive "
               "focal length, so such a lens is not supported";
        return PrescriptionError{msg.str(), 0};
    }
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

ParaxialData paraxial_data(const Prescription& lens, double stop_mm, double image_distance_mm)
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
    // The aperture the pupils image: the stop, or the one that limits the axial beam.
    int a = k;
    double a_mm = p.stop_mm;
    if (std::isfinite(image_distance_mm)) {
        const AxialLimit limit = axial_limit_sized(lens, p.stop_mm, image_distance_mm);
        if (!limit.valid)
            return p;
        a = limit.surface;
        a_mm = a == k ? p.stop_mm : lens.surfaces[a].aperture_mm;
        p.largest_stop_mm = limit.largest_stop_mm;
    }
    p.aperture_surface = a;
    p.aperture_z = z[a];
    p.aperture_mm = a_mm;
    // Entrance pupil: the aperture imaged by the surfaces in front of it, seen from object space
    // (a rim lies on its own surface, whose refraction leaves it where it is).
    Mat2 F = kIdentity;
    if (a > 0)
        F = transfer(lens.surfaces[a - 1].thickness_mm, medium_after(lens, a - 1)) * system_matrix(lens, 0, a - 1);
    if (F.a == 0)
        return p;  // entrance pupil at infinity
    p.entrance_pupil_z = F.b / F.a;
    p.entrance_pupil_mm = a_mm / std::fabs(F.a);
    // Exit pupil: the aperture imaged by the surfaces behind it, seen from image space.
    Mat2 B = kIdentity;
    if (a < count - 1)
        B = system_matrix(lens, a + 1, count - 1) * transfer(lens.surfaces[a].thickness_mm, medium_after(lens, a));
    if (B.d == 0)
        return p;  // exit pupil at infinity
    const double s = -B.b / B.d;
    p.exit_pupil_z = p.rear_vertex_z + s;
    p.exit_pupil_mm = a_mm * std::fabs(B.a + s * B.c);
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
    lens_.blade_rotation_deg = reduced_blade_rotation(lens.blade_rotation_deg, lens.blades);
    double n = 1;
    for (size_t i = 0; i < lens.surfaces.size(); ++i) {
        before_[i] = n;
        if (!lens.surfaces[i].stop)
            n = lens.surfaces[i].ior;
        after_[i] = lens.surfaces[i].stop ? before_[i] : lens.surfaces[i].ior;
        aspheric_.push_back(!lens.surfaces[i].stop && lens.surfaces[i].is_aspheric() ? 1 : 0);
        any_aspheric_ = any_aspheric_ || aspheric_.back() != 0;
    }
}

Traced TracingLens::trace_from_image(const LensRay& in) const
{
    if (any_aspheric_)
        return trace_aspheric(lens_, z_.data(), before_.data(), after_.data(), aspheric_.data(), in, true);
    return trace<false>(lens_, z_.data(), before_.data(), after_.data(), nullptr, in, true);
}

Traced TracingLens::trace_from_object(const LensRay& in) const
{
    if (any_aspheric_)
        return trace_aspheric(lens_, z_.data(), before_.data(), after_.data(), aspheric_.data(), in, false);
    return trace<false>(lens_, z_.data(), before_.data(), after_.data(), nullptr, in, false);
}

Traced trace_from_image(const Prescription& lens, const LensRay& in) { return TracingLens(lens).trace_from_image(in); }
Traced trace_from_object(const Prescription& lens, const LensRay& in) { return TracingLens(lens).trace_from_object(in); }

bool dispersive(const Prescription& lens)
{
    for (const LensSurface& s : lens.surfaces)
        if (s.glass.dispersive())
            return true;
    return false;
}

Prescription prescription_at_wavelength(const Prescription& lens, double wavelength_nm)
{
    Prescription at = lens;
    for (LensSurface& s : at.surfaces)
        if (s.glass.dispersive()) {
            s.ior = s.index_at(wavelength_nm);
            s.glass = Glass();
        }
    return at;
}

ChromaticFocus chromatic_focus(const Prescription& lens)
{
    ChromaticFocus focus;
    if (!dispersive(lens))
        return focus;
    const char* names[3] = {"F", "d", "C"};
    const double wavelengths[3] = {kLineFNm, kLineDNm, kLineCNm};
    for (int k = 0; k < 3; ++k) {
        const Prescription at = prescription_at_wavelength(lens, wavelengths[k]);
        const int count = int(at.surfaces.size());
        const Mat2 S = system_matrix(at, 0, count - 1);
        if (S.c == 0)
            return focus;
        const double efl = -1 / S.c;
        focus.lines[k] = LineFocus{names[k], wavelengths[k], efl, S.a * efl};
    }
    focus.longitudinal_colour_mm = focus.lines[0].bfd_mm - focus.lines[2].bfd_mm;
    focus.valid = std::isfinite(focus.longitudinal_colour_mm);
    return focus;
}

double stop_diameter_for_f_number(const Prescription& lens, double f_number)
{
    const ParaxialData full = paraxial_data(lens);
    if (!full.valid || !(f_number > 0))
        return NAN;
    // The entrance pupil scales with the stop: EP = stop / |F.a|.
    const double ratio = full.entrance_pupil_mm / full.stop_mm;
    return full.efl_mm / f_number / ratio;
}

double f_number_for_stop_diameter(const Prescription& lens, double stop_mm)
{
    const ParaxialData full = paraxial_data(lens);
    if (!full.valid || !(stop_mm > 0))
        return NAN;
    return full.efl_mm / (stop_mm * full.entrance_pupil_mm / full.stop_mm);
}

AxialLimit axial_limit(const Prescription& lens, double image_distance_mm)
{
    const int k = stop_index(lens);
    return axial_limit_sized(lens, k >= 0 ? lens.surfaces[size_t(k)].aperture_mm : 0, image_distance_mm);
}

} // namespace plenoptic
