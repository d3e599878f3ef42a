// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic-lens-data: what the optics core says of a lens file, as JSON, for plenoptic-lens (the
// Python front end: info and draw) and for scripts.
//
//   plenoptic-lens-data [--field DEG ...] [--name NAME] LENS.dat
//   plenoptic-lens-data [--field DEG ...] [--name NAME] -        (the lens file on standard input)
//
// Everything here is the optics library's (lens/prescription.h): parse_lens_file, paraxial_data,
// chromatic_focus, vertex_positions, surface_sag_mm and trace_from_object; this program only
// chooses the rays and writes the answers down.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "plenoptic/lens/prescription.h"

namespace {

using Json = nlohmann::ordered_json;
using plenoptic::LensRay;
using plenoptic::Prescription;
using plenoptic::TraceResult;
using plenoptic::Traced;
using plenoptic::Vec3;

const double kPi = 3.14159265358979323846;

const char* kUsage =
    "usage: plenoptic-lens-data [--field DEG ...] [--name NAME] LENS.dat\n"
    "       plenoptic-lens-data [--field DEG ...] [--name NAME] -      (the lens file on standard input)\n"
    "Prints, as one JSON document, what the optics core says of a lens file (pbrt's rows, as\n"
    "main_lens { lens_file } reads them), for an object at infinity and the stop as written:\n"
    "  surfaces      each row with its vertex z and its profile (r, z) over its clear aperture\n"
    "  paraxial      EFL, back and front focal distances, focal and principal planes, entrance\n"
    "                and exit pupils (z and diameter), the stop, the f-number (lengths in mm, z from\n"
    "                the front vertex, +z towards the image)\n"
    "  chromatic     with dispersion: EFL and back focus at the F, d and C lines, longitudinal colour\n"
    "  largest_field_deg  the largest field angle whose chief ray passes every clear aperture\n"
    "  rays          for the axis and each --field: the chief ray and the two marginal rays (aimed\n"
    "                at the stop's centre and edges by real-ray iteration), each as the points where\n"
    "                it meets each surface, then the paraxial image plane; a blocked ray stops there\n"
    "                and says why; for a marginal ray a rim blocks, the beam's edge on that side\n"
    "                (the ray through the largest fraction of the stop's radius that passes)\n"
    "  --name NAME   the name refusals give the file (default: its path, or 'standard input')\n"
    "Exit status: 0 done; 1 the lens is refused (one line on standard error, and\n"
    "{\"error\": {\"message\", \"line\"}} on standard output); 2 bad usage or an unreadable file.\n";

int usage_error(const std::string& message)
{
    std::fprintf(stderr, "plenoptic-lens-data: %s\n", message.c_str());
    return 2;
}

bool parse_number(const std::string& text, double* value)
{
    if (text.empty())
        return false;
    char* end = nullptr;
    *value = std::strtod(text.c_str(), &end);
    return end == text.c_str() + text.size() && std::isfinite(*value);
}

const char* result_name(TraceResult r)
{
    switch (r) {
    case TraceResult::Passed: return "passed";
    case TraceResult::Missed: return "missed the surface";
    case TraceResult::ClearAperture: return "outside the clear aperture";
    case TraceResult::Stop: return "outside the stop";
    case TraceResult::TotalInternalReflection: return "total internal reflection";
    }
    return "?";
}

// The surfaces up to and including `last`.
Prescription prefix(const Prescription& lens, int last)
{
    Prescription p = lens;
    p.surfaces.resize(size_t(last) + 1);
    return p;
}

// A ray's path: where it meets each surface, as the optics core traces it (the trace of the
// first i + 1 surfaces ends on surface i).
struct Path {
    std::vector<Vec3> points;
    TraceResult result = TraceResult::Passed;
    int surface = -1;  // the surface that blocked it
    Vec3 dir{0, 0, 1};  // leaving the last surface (when it passed)
};

Path trace_path(const Prescription& lens, const LensRay& ray)
{
    Path path;
    path.points.push_back(ray.origin);
    for (int i = 0; i < int(lens.surfaces.size()); ++i) {
        const Traced t = plenoptic::trace_from_object(prefix(lens, i), ray);
        if (t.result != TraceResult::Passed) {
            if (t.result != TraceResult::Missed)
                path.points.push_back(t.ray.origin);  // the point where it was blocked
            path.result = t.result;
            path.surface = t.surface;
            return path;
        }
        path.points.push_back(t.ray.origin);
        path.dir = t.ray.dir;
    }
    return path;
}

// Aiming: the ray of direction `dir` that crosses the stop's plane at height `target` (meridional
// plane y-z), found by the secant method on its height y0 at the start plane z0, tracing the
// surfaces up to the stop with every clear aperture opened (aiming finds the ray; the real trace
// then says whether the apertures pass it). False when no such ray is found.
bool aim(const Prescription& lens, int stop, Vec3 dir, double z0, double target, double y_guess, double* y0)
{
    Prescription open = prefix(lens, stop);
    for (plenoptic::LensSurface& s : open.surfaces)
        s.aperture_mm = 1e12;
    auto height = [&](double y, double* at) {
        const Traced t = plenoptic::trace_from_object(open, LensRay{Vec3{0, y, z0}, dir});
        if (t.result != TraceResult::Passed)
            return false;
        *at = t.ray.origin.y;
        return true;
    };
    const double scale = std::max(1.0, 0.5 * lens.surfaces[size_t(stop)].aperture_mm);
    double ya = y_guess, fa;
    if (!height(ya, &fa))
        return false;
    double yb = y_guess + 1e-3 * scale, fb;
    if (!height(yb, &fb))
        return false;
    for (int iteration = 0; iteration < 100; ++iteration) {
        if (std::fabs(fb - target) < 1e-10 * scale) {
            *y0 = yb;
            return true;
        }
        if (fb == fa)
            return false;
        double yc = yb - (fb - target) * (yb - ya) / (fb - fa);
        double fc;
        // A step that leaves the surfaces' spheres: halve it towards the last good point.
        int tries = 0;
        while (!height(yc, &fc) && tries++ < 40)
            yc = 0.5 * (yc + yb);
        if (tries > 40)
            return false;
        ya = yb, fa = fb;
        yb = yc, fb = fc;
    }
    return false;
}

struct RayJob {
    double field_deg;
    const char* name;  // "chief", "upper marginal", "lower marginal"
    double stop_fraction;  // target height at the stop over its radius: 0, +1, -1
};

} // namespace

int main(int argc, char** argv)
{
    std::vector<std::string> args(argv + 1, argv + argc);
    std::vector<double> fields;
    std::string name, path;
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "-h" || args[i] == "--help") {
            std::fputs(kUsage, stdout);
            return 0;
        }
        if (args[i] == "--field" || args[i] == "--name") {
            if (i + 1 >= args.size())
                return usage_error(args[i] + " needs a value");
            if (args[i] == "--name") {
                name = args[++i];
                continue;
            }
            double deg;
            if (!parse_number(args[++i], &deg) || !(deg > -90 && deg < 90))
                return usage_error("--field '" + args[i] + "': a field angle in degrees, above -90 and below 90");
            fields.push_back(deg);
            continue;
        }
        if (!path.empty())
            return usage_error("one lens file only ('" + path + "' and '" + args[i] + "')\n" + kUsage);
        path = args[i];
    }
    if (path.empty())
        return usage_error(std::string("missing LENS.dat (or - for standard input)\n") + kUsage);

    std::string text;
    if (path == "-") {
        std::ostringstream all;
        all << std::cin.rdbuf();
        text = all.str();
        if (name.empty())
            name = "standard input";
    } else {
        std::ifstream in(path, std::ios::binary);
        if (!in)
            return usage_error(path + ": cannot read it");
        std::ostringstream all;
        all << in.rdbuf();
        text = all.str();
        if (name.empty())
            name = path;
    }

    const plenoptic::ParsedPrescription parsed = plenoptic::parse_lens_file(text);
    if (parsed.error.any()) {
        const std::string where = name + (parsed.error.line > 0 ? ":" + std::to_string(parsed.error.line) : "");
        std::fprintf(stderr, "plenoptic-lens-data: %s: %s\n", where.c_str(), parsed.error.message.c_str());
        Json out;
        out["error"] = Json{{"message", parsed.error.message}, {"line", parsed.error.line}};
        std::cout << out.dump(1) << "\n";
        return 1;
    }
    const Prescription& lens = parsed.prescription;
    const int count = int(lens.surfaces.size());
    const std::vector<double> z = plenoptic::vertex_positions(lens);
    const plenoptic::ParaxialData p = plenoptic::paraxial_data(lens);
    int stop = 0;
    while (!lens.surfaces[size_t(stop)].stop)
        ++stop;

    Json out;
    out["name"] = name;
    Json surfaces = Json::array();
    double z_min = 0, z_max = z[size_t(count - 1)], r_max = 0;
    const int profile_points = 81;
    for (int i = 0; i < count; ++i) {
        const plenoptic::LensSurface& s = lens.surfaces[size_t(i)];
        Json row;
        row["row"] = i + 1;
        row["line"] = s.line;
        row["stop"] = s.stop;
        row["radius_mm"] = s.radius_mm;
        row["thickness_mm"] = s.thickness_mm;
        row["ior"] = s.ior;
        row["abbe_number"] = s.glass.abbe;
        row["aperture_mm"] = s.aperture_mm;
        row["vertex_z_mm"] = z[size_t(i)];
        Json profile = Json::array();
        const double a = 0.5 * s.aperture_mm;
        r_max = std::max(r_max, a);
        for (int k = 0; k < profile_points && !s.stop; ++k) {
            const double r = -a + 2 * a * k / (profile_points - 1);
            const double zz = z[size_t(i)] + plenoptic::surface_sag_mm(s, r);
            profile.push_back(Json::array({r, zz}));
            if (std::isfinite(zz))
                z_min = std::min(z_min, zz), z_max = std::max(z_max, zz);
        }
        row["profile"] = profile;
        surfaces.push_back(row);
    }
    out["surfaces"] = surfaces;

    Json par;
    par["valid"] = p.valid;
    par["efl_mm"] = p.efl_mm;
    par["bfd_mm"] = p.bfd_mm;
    par["ffd_mm"] = p.ffd_mm;
    par["rear_vertex_z_mm"] = p.rear_vertex_z;
    par["front_focal_z_mm"] = p.front_focal_z;
    par["rear_focal_z_mm"] = p.rear_focal_z;
    par["front_principal_z_mm"] = p.front_principal_z;
    par["rear_principal_z_mm"] = p.rear_principal_z;
    par["entrance_pupil_z_mm"] = p.entrance_pupil_z;
    par["entrance_pupil_mm"] = p.entrance_pupil_mm;
    par["exit_pupil_z_mm"] = p.exit_pupil_z;
    par["exit_pupil_mm"] = p.exit_pupil_mm;
    par["stop_row"] = stop + 1;
    par["stop_z_mm"] = p.stop_z;
    par["stop_mm"] = p.stop_mm;
    par["f_number"] = p.f_number;
    out["paraxial"] = par;

    out["dispersive"] = plenoptic::dispersive(lens);
    if (plenoptic::dispersive(lens)) {
        const plenoptic::ChromaticFocus c = plenoptic::chromatic_focus(lens);
        Json chromatic;
        chromatic["valid"] = c.valid;
        Json lines = Json::array();
        for (const plenoptic::LineFocus& l : c.lines)
            lines.push_back(Json{{"line", l.line}, {"wavelength_nm", l.wavelength_nm}, {"efl_mm", l.efl_mm},
                                 {"bfd_mm", l.bfd_mm}});
        chromatic["lines"] = lines;
        chromatic["longitudinal_colour_mm"] = c.longitudinal_colour_mm;
        out["chromatic"] = chromatic;
    }

    // The rays start on a plane in front of everything drawn, at infinity's direction.
    const double image_z = p.valid ? p.rear_focal_z : z[size_t(count - 1)];
    z_min = std::min(z_min, p.entrance_pupil_z);
    const double span = std::max(image_z, z_max) - z_min;
    const double z0 = z_min - 0.2 * span;
    out["image_plane_z_mm"] = image_z;
    out["rays_start_z_mm"] = z0;

    const double stop_r = 0.5 * lens.surfaces[size_t(stop)].aperture_mm;
    const double pupil_ratio = p.valid && p.stop_mm > 0 ? p.entrance_pupil_mm / p.stop_mm : 1;
    // The ray of field angle `deg` through the stop at `fraction` of its radius (the marginal rays
    // a hair inside the edge, which the stop then passes), aimed by real rays: from the paraxial
    // guess on the axis, then by continuation in steps of at most 2 degrees, each step starting
    // from the last one's ray (the entrance pupil of a wide angle moves with the field). Failing
    // that, the ray through the paraxial entrance pupil.
    auto make_ray = [&](double deg, double fraction, bool* real) {
        // The chief ray a hair (1e-6 of the stop's radius) above the stop's centre: a stop of
        // thickness 0 in front of a curved surface puts the centre on that surface's vertex, and
        // the core's trace meets a surface only strictly ahead of a ray's origin; within about
        // 1e-6 mm of the vertex the sphere's root is lost in rounding (seen: a chief ray at
        // 1e-8 mm from the axis missed a 44.7 mm radius).
        const double target = fraction == 0 ? 1e-6 * stop_r : fraction * stop_r * (1 - 1e-9);
        auto direction = [](double d) {
            const double t = d * kPi / 180;
            return Vec3{0, std::sin(t), std::cos(t)};
        };
        const double t = deg * kPi / 180;
        const double paraxial = fraction * stop_r * pupil_ratio + (z0 - p.entrance_pupil_z) * std::tan(t);
        double y0 = fraction * stop_r * pupil_ratio;
        *real = aim(lens, stop, direction(0), z0, target, y0, &y0);
        const int steps = int(std::ceil(std::fabs(deg) / 2));
        for (int k = 1; k <= steps && *real; ++k) {
            const double d = deg * k / steps;
            const double previous = deg * (k - 1) / steps;
            // The last ray, turned about the entrance pupil's centre, is the next guess.
            const double guess = y0 + (z0 - p.entrance_pupil_z) *
                                          (std::tan(d * kPi / 180) - std::tan(previous * kPi / 180));
            *real = aim(lens, stop, direction(d), z0, target, guess, &y0);
        }
        if (!*real)
            y0 = paraxial;
        return LensRay{Vec3{0, y0, z0}, direction(deg)};
    };
    auto chief_passes = [&](double deg) {
        bool real;
        const LensRay ray = make_ray(deg, 0, &real);
        return real && trace_path(lens, ray).result == TraceResult::Passed;
    };
    double largest = 0;
    if (chief_passes(0)) {
        double lo = 0, hi = 89.9;
        if (chief_passes(hi))
            lo = hi;
        else
            for (int k = 0; k < 40; ++k) {
                const double mid = 0.5 * (lo + hi);
                (chief_passes(mid) ? lo : hi) = mid;
            }
        largest = lo;
    }
    out["largest_field_deg"] = largest;

    std::vector<double> angles{0};
    for (double f : fields)
        if (f != 0)
            angles.push_back(f);
    Json rays = Json::array();
    auto ray_json = [&](double deg, const char* ray_name, double fraction, bool real, const Path& path) {
        Json points = Json::array();
        for (const Vec3& v : path.points)
            points.push_back(Json::array({v.y, v.z}));
        Json r;
        r["field_deg"] = deg;
        r["ray"] = ray_name;
        r["stop_fraction"] = fraction;
        r["aimed"] = real ? "real" : "paraxial";
        r["result"] = result_name(path.result);
        r["blocked_by_row"] = path.surface >= 0 ? Json(path.surface + 1) : Json(nullptr);
        r["points"] = points;  // [y, z] in mm: the start, each surface met, the image plane
        return r;
    };
    auto traced = [&](double deg, double fraction, bool* real) {
        Path path = trace_path(lens, make_ray(deg, fraction, real));
        if (path.result == TraceResult::Passed && path.dir.z > 0) {
            const Vec3 last = path.points.back();
            path.points.push_back(last + ((image_z - last.z) / path.dir.z) * path.dir);
        }
        return path;
    };
    for (double deg : angles) {
        const RayJob jobs[3] = {{deg, "upper marginal", 1}, {deg, "lower marginal", -1}, {deg, "chief", 0}};
        bool chief_real;
        const Path chief = traced(deg, 0, &chief_real);
        for (const RayJob& job : jobs) {
            bool real;
            const Path path = job.stop_fraction == 0 ? chief : traced(deg, job.stop_fraction, &real);
            if (job.stop_fraction == 0)
                real = chief_real;
            rays.push_back(ray_json(deg, job.name, job.stop_fraction, real, path));
            // A marginal ray that a rim blocks while the chief ray passes: the beam's edge, the ray
            // through the largest part of the stop's radius on that side that still passes (by
            // bisection: the vignetted beam an optical designer draws).
            if (job.stop_fraction == 0 || path.result == TraceResult::Passed || chief.result != TraceResult::Passed)
                continue;
            double lo = 0, hi = 1;
            for (int k = 0; k < 40; ++k) {
                const double mid = 0.5 * (lo + hi);
                bool r;
                (traced(deg, job.stop_fraction * mid, &r).result == TraceResult::Passed && r ? lo : hi) = mid;
            }
            if (lo > 0) {
                bool r;
                const Path edge = traced(deg, job.stop_fraction * lo, &r);
                rays.push_back(ray_json(deg, job.stop_fraction > 0 ? "upper beam edge" : "lower beam edge",
                                        job.stop_fraction * lo, r, edge));
            }
        }
    }
    out["rays"] = rays;
    std::cout << out.dump(1) << "\n";
    return std::fflush(stdout) == 0 ? 0 : 2;
}
