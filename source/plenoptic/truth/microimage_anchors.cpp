// SPDX-License-Identifier: AGPL-3.0-or-later
// The microimage truth between anchors (see the header).

#include "plenoptic/truth/microimage_anchors.h"

#include "plenoptic/projection/microimage_lattice.h"

namespace plenoptic {
namespace microimage_detail {

namespace {

// The interpolation is used where cubic_error's estimate is below these, half the accuracy the
// truth keeps (0.001 px, 1e-4 of lit fraction): the measured lenses themselves scatter about a
// smooth field by some 1e-4 px and 3e-5 of lit fraction (small regions near the cell's edge found or
// missed, the cell's band cut differently by the 24 x 24 cell points from lens to lens), which the
// interpolation does not follow, and which gives fourth differences of up to about 1.5e-3 px and
// 3e-4 where the field itself is smooth.
const double kInterpolatedPx = 5e-4;
const double kInterpolatedFraction = 5e-5;

// The margin on cubic_error's estimate.
const double kCubicMargin = 1.5;

} // namespace

double lattice_x(GridType grid, LensIndex lens)
{
    return double(lens.k) + (grid == GridType::Hexagonal && floor_mod(lens.l, 2) == 1 ? 0.5 : 0.0);
}

void cubic_weights(double t, double w[4])
{
    w[0] = -(t - 1) * (t - 2) * (t - 3) / 6;
    w[1] = t * (t - 2) * (t - 3) / 2;
    w[2] = -t * (t - 1) * (t - 3) / 2;
    w[3] = t * (t - 1) * (t - 2) / 6;
}

double cubic_error(double t, double fourth_difference)
{
    return kCubicMargin * std::fabs(t * (t - 1) * (t - 2) * (t - 3)) / 24 * fourth_difference;
}

bool interpolate(const Anchors& a, Vec2 at, MicroimageTruth* truth, Vec2 lattice_px)
{
    std::int64_t i0, j0;
    double x, y;
    a.stencil(at, &i0, &j0, &x, &y);
    // The anchors it reads, in a 6 x 6 block from (i0 - 1, j0 - 1); null where not read.
    const AnchorValue* block[6][6] = {};
    bool dark = false;
    bool lobe = false;
    a.each(i0, j0, [&](std::int64_t i, std::int64_t j) {
        const auto found = a.values->find(anchor_key(a.lens(i, j)));
        if (found == a.values->end() || !found->second.lit) {
            dark = true;
        } else {
            block[j - j0 + 1][i - i0 + 1] = &found->second;
            lobe = lobe || found->second.lobe;
        }
    });
    if (dark || lobe)
        return false;
    auto v = [&](std::int64_t i, std::int64_t j, int q) { return block[j - j0 + 1][i - i0 + 1]->value[q]; };
    const double allowed[3] = {kInterpolatedPx, kInterpolatedPx, kInterpolatedFraction};
    double result[3];
    for (int q = 0; q < 3; ++q) {
        double error;
        result[q] = cubic_through(a, i0, j0, x, y, v, q, &error);
        if (error > allowed[q])
            return false;
    }
    truth->lit = true;
    truth->u_px = lattice_px.x + result[0];
    truth->v_px = lattice_px.y + result[1];
    truth->lit_fraction = result[2];
    return true;
}

bool interpolates(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options)
{
    return options.anchor_step >= 4 && options.anchor_step % 2 == 0 && m.array.microlens &&
           m.array.microlens->forms_image() && !m.array.microlens->first_order_exact() && !m.array.errors &&
           !light.array.errors && (m.array.grid == GridType::Hexagonal || m.array.grid == GridType::Rectangular);
}

void Anchors::cover(std::int64_t s, const double range[4])
{
    step = s;
    k0 = std::int64_t(std::floor(range[0] / double(s))) - 1;
    k1 = std::int64_t(std::floor(range[1] / double(s))) + 2;
    l0 = std::int64_t(std::floor(range[2] / double(s))) - 1;
    l1 = std::int64_t(std::floor(range[3] / double(s))) + 2;
}

Canonical::Canonical(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options)
    : m_(m), light_(light)
{
    const ArrayPose& pose = m.array.pose;
    const bool about_axis = pose.normal.x == 0 && pose.normal.y == 0 && pose.normal.z == 1 && !pose.tilted;
    auto equal = [](Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
    const bool same = equal(light.array.pose.centre_mm, pose.centre_mm) &&
                      equal(light.array.pose.normal, pose.normal) &&
                      equal(mul(light.array.pose.rotation, Vec3{1, 0, 0}), mul(pose.rotation, Vec3{1, 0, 0}));
    if (!options.symmetry || !about_axis || !same || Symmetry(m, light, options).valid())
        return;
    const double none[3] = {0, 0, 0};
    const ArrayPose canonical = make_array_pose(none, Vec3{0, 0, pose.centre_mm.z});
    model_ = m;
    model_.array.pose = canonical;
    light_model_ = light;
    light_model_.array.pose = canonical;
    if (!Symmetry(model_, light_model_, options).valid())
        return;
    const Vec3 x = mul(pose.rotation, Vec3{1, 0, 0});
    turn_[0] = x.x;
    turn_[1] = x.y;
    active_ = true;
}

Vec2 Canonical::position(LensIndex lens, Vec2 shift) const
{
    if (!active_ && shift.x == 0 && shift.y == 0)
        return Vec2{lattice_x(m_.array.grid, lens), double(lens.l)};
    const Vec2 c = canonical_local(lens, shift);
    return Vec2{c.x / m_.array.pitch_mm, c.y / m_.array.row_spacing_mm()};
}

bool Canonical::centre_px(LensIndex lens, Vec2* px, Vec2 shift) const
{
    if (!active_ && shift.x == 0 && shift.y == 0) {
        const MicroimageCentre c = microimage_centre_px(m_, lens);
        *px = Vec2{c.u, c.v};
        return c.valid;
    }
    const Vec2 c = canonical_local(lens, shift);
    return project_to_sensor_px(model(), model().array.to_optics(Vec3{c.x, c.y, 0}), px);
}

Vec2 Canonical::to_camera_px(Vec2 px) const
{
    if (!active_)
        return px;
    const Vec3 p = m_.sensor.point(px.x + 0.5, px.y + 0.5);
    const PixelPoint out = m_.sensor.to_pixel(turn_[0] * p.x - turn_[1] * p.y, turn_[1] * p.x + turn_[0] * p.y);
    return Vec2{out.u, out.v};
}

Vec2 Canonical::canonical_local(LensIndex lens, Vec2 shift) const
{
    const Vec2 c = m_.array.lattice_centre_local(lens);
    if (!active_)
        return Vec2{c.x + shift.x, c.y + shift.y};
    const Vec3 q = m_.array.to_optics(Vec3{c.x + shift.x, c.y + shift.y, 0});
    return Vec2{turn_[0] * q.x + turn_[1] * q.y, -turn_[1] * q.x + turn_[0] * q.y};
}

} // namespace microimage_detail
} // namespace plenoptic
