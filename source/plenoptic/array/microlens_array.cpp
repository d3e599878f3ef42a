// SPDX-License-Identifier: AGPL-3.0-or-later
// The microlens array: its pose and its construction.

#include "plenoptic/array/microlens_array.h"

#include "plenoptic/array/refracting_microlens.h"
#include "plenoptic/lens/glass.h"

#include "plenoptic/core/json.h"

#include <cmath>
#include <utility>

namespace plenoptic {

namespace {

// sin and cos of an angle in degrees, exact at multiples of 90 degrees so that an unrotated or
// quarter-turned array stays exactly axis-aligned.
void sin_cos_degrees(double degrees, double* s, double* c)
{
    const double reduced = std::fmod(degrees, 360.0);  // exact
    const double quarter = reduced / 90.0;
    if (quarter == std::floor(quarter)) {
        static const double sines[4] = {0, 1, 0, -1};
        const int q = int(((long long)quarter % 4 + 4) % 4);
        *s = sines[q];
        *c = sines[(q + 1) % 4];
        return;
    }
    const double radians = reduced * (kPi / 180.0);
    *s = std::sin(radians);
    *c = std::cos(radians);
}

} // namespace

Mat3 rotation_from_degrees(const double degrees[3])
{
    double sx, cx, sy, cy, sz, cz;
    sin_cos_degrees(degrees[0], &sx, &cx);
    sin_cos_degrees(degrees[1], &sy, &cy);
    sin_cos_degrees(degrees[2], &sz, &cz);
    // Column-vector forms of POV-Ray's row-vector matrices (its [1][2] = sin x is our [2][1]).
    const Mat3 rx = {{{1, 0, 0}, {0, cx, -sx}, {0, sx, cx}}};
    const Mat3 ry = {{{cy, 0, sy}, {0, 1, 0}, {-sy, 0, cy}}};
    const Mat3 rz = {{{cz, -sz, 0}, {sz, cz, 0}, {0, 0, 1}}};
    return mul(rz, mul(ry, rx));
}

ArrayPose make_array_pose(const double rotate_deg[3], Vec3 centre_mm)
{
    ArrayPose pose;
    pose.rotation = rotation_from_degrees(rotate_deg);
    pose.centre_mm = centre_mm;
    pose.normal = mul(pose.rotation, Vec3{0, 0, 1});
    pose.tilted = !(pose.rotation.m[0][2] == 0 && pose.rotation.m[1][2] == 0);
    pose.tilt_sine = std::hypot(pose.normal.x, pose.normal.y);
    return pose;
}

MicrolensArray no_microlens_array(double plane_z)
{
    const double no_rotation[3] = {0, 0, 0};
    MicrolensArray array;
    array.grid = GridType::None;
    array.pitch_mm = 0;
    array.microlens = nullptr;
    array.lens_type_count = 1;
    array.distance_mm = 0;
    array.pose = make_array_pose(no_rotation, Vec3{0, 0, plane_z});
    array.cell_inradius_mm = 0;
    array.cell_circumradius_mm = 0;
    return array;
}

MicrolensArray make_microlens_array(GridType grid, double pitch_mm, std::shared_ptr<const Microlens> microlens,
                                    double distance_mm, const ArrayPose& pose)
{
    MicrolensArray array;
    array.grid = grid;
    array.pitch_mm = pitch_mm;
    array.lens_type_count = microlens->type_count();
    array.microlens = std::move(microlens);
    array.distance_mm = distance_mm;
    array.pose = pose;
    array.cell_inradius_mm = cell_inradius(grid, pitch_mm);
    array.cell_circumradius_mm = cell_circumradius(grid, pitch_mm);
    return array;
}

LensIndex MicrolensArray::nearest_displaced(LensIndex lattice, double x, double y) const
{
    // Every displacement is below a quarter of the pitch (kErrorSigmas and the checks), so the lens
    // whose actual centre is nearest is the lattice cell's or one of its neighbours'. A neighbour
    // whose lattice point is farther than the best distance so far plus the largest shift cannot
    // be nearer: its error is not looked up (most points are well inside their cells).
    const double shift = errors->max_shift_mm();
    LensIndex best = lattice;
    const Vec2 c0 = centre_local(lattice);
    double best_sq = (x - c0.x) * (x - c0.x) + (y - c0.y) * (y - c0.y);
    LensIndex adjacent[8];
    const int n_adjacent = adjacent_lenses(grid, lattice, adjacent);
    for (int q = 0; q < n_adjacent; ++q) {
        const LensIndex lens = adjacent[q];
        const Vec2 n = lattice_centre_local(lens);
        const double reach = std::sqrt(best_sq) + shift;
        if ((x - n.x) * (x - n.x) + (y - n.y) * (y - n.y) > reach * reach)
            continue;
        const Vec2 c = centre_local(lens);
        const double sq = (x - c.x) * (x - c.x) + (y - c.y) * (y - c.y);
        if (sq < best_sq) {
            best_sq = sq;
            best = lens;
        }
    }
    return best;
}

MicrolensArray MicrolensArray::at_wavelength(double wavelength_nm) const
{
    MicrolensArray out = *this;
    if (abbe == 0 || !microlens)
        return out;
    std::shared_ptr<const Microlens> scaled = microlens->with_power_scaled(two_term_power_ratio(abbe, wavelength_nm));
    if (scaled)
        out.microlens = std::move(scaled);
    return out;
}

MetadataJson MicrolensArray::metadata(const double rotate_deg[3], const double translate_mm[3]) const
{
    MetadataJson json = MetadataJson::object();
    json["grid"] = grid == GridType::Hexagonal ? "hexagonal" : "rectangular";
    json["lens"] = microlens->kind_name();
    json["pitch_mm"] = json_number(pitch_mm);
    const std::vector<double> focal_lengths = microlens->focal_lengths_mm();
    json["focal_lengths_mm"] = json_numbers(focal_lengths.data(), int(focal_lengths.size()));
    json["distance_mm"] = json_number(distance_mm);
    json["rotate_deg"] = json_numbers(rotate_deg, 3);
    json["translate_mm"] = json_numbers(translate_mm, 3);
    if (abbe != 0)
        json["abbe_number"] = json_number(abbe);
    if (errors || fill_factor != 1 || mask || baffles) {
        json["fill_factor"] = json_number(fill_factor);
        json["gap"] = fill_factor == 1 ? "none" : (mask ? "masked" : "clear");
        json["baffles"] = baffles;
    }
    if (errors)
        json["errors"] = errors->metadata();
    if (const RefractingShape* shape = refracting_shape(*microlens)) {
        // The lenses' shape as written, and their paraxial (first-order) data: the effective focal
        // length (also focal_lengths_mm) and the principal planes, measured from the array's plane
        // (its face nearest the sensor) towards the scene.
        MetadataJson lens = MetadataJson::object();
        MetadataJson surface = MetadataJson::object();
        surface["radius_mm"] = json_number(shape->radius_mm);
        surface["conic"] = json_number(shape->conic);
        lens["surface"] = surface;
        lens["ior"] = json_number(shape->ior);
        lens["thickness_mm"] = json_number(shape->cap_mm);
        lens["substrate_mm"] = json_number(shape->substrate_mm);
        lens["curved_side"] = shape->curved_towards_scene ? "scene" : "sensor";
        lens["paraxial_focal_length_mm"] = json_number(shape->focal_length_mm());
        MetadataJson planes = MetadataJson::object();
        planes["front_mm"] = json_number(shape->front_principal_z());
        planes["rear_mm"] = json_number(shape->rear_principal_z());
        lens["principal_planes"] = planes;
        json["refracting"] = lens;
    }
    return json;
}

} // namespace plenoptic
