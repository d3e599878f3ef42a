// SPDX-License-Identifier: AGPL-3.0-or-later
// Microimage ground truth: each lens's white-scene microimage, integrated through the renderer's
// own rays (see the header): which lenses, and how each is found (measured, truth/
// microimage_measure.h; between anchors, truth/microimage_anchors.h; corrected for manufacturing
// errors, truth/microimage_errors.h); the lattice fit and the CSV.

#include "plenoptic/truth/microimages.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <unordered_map>

#include "plenoptic/array/refracting_microlens.h"
#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/truth/microimage_anchors.h"
#include "plenoptic/truth/microimage_errors.h"
#include "plenoptic/truth/microimage_measure.h"

namespace plenoptic {

using namespace microimage_detail;

MicroimageOptions default_microimage_options()
{
    MicroimageOptions options;
    options.azimuths = 32;
    options.tolerance_px = 1e-3;
    options.aperture_points = 3;
    options.threads = 0;
    options.reuse_neighbours = true;
    options.anchor_step = 16;
    options.refracting_points = 24;
    return options;
}

std::vector<MicroimageTruth> microimage_truth(const PlenopticCamera& m, const MicroimageOptions& options,
                                              const MicroimageProgress& progress, const MicroimageCancel& cancelled,
                                              const PlenopticCamera* through, MicroimageWork* work)
{
    MicroimageWork unused;
    MicroimageWork& counts = work ? *work : unused;
    counts = MicroimageWork();
    // The lenses and their start points are this camera's; their light is traced through `through`.
    const PlenopticCamera& light = through ? *through : m;
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    std::vector<MicroimageTruth> out;
    if (m.array.grid == GridType::None || !m.lens || W <= 0 || H <= 0)
        return out;
    double box[4];
    if (!picture_on_array(m, box))
        return out;
    const double p = m.array.pitch_mm, rows = row_spacing(m.array.grid, p);
    // Margins of lenses: a lattice centre in the picture may belong to a lens whose centre
    // projects just outside the box of the corners (the centres project from the exit pupil).
    const double l0 = std::floor(box[1] / rows) - 2, l1 = std::ceil(box[3] / rows) + 2;
    const double k0 = std::floor(box[0] / p) - 3, k1 = std::ceil(box[2] / p) + 3;
    if (!(l1 - l0 < 1e7 && k1 - k0 < 1e7))
        return out;
    // The lenses whose lattice centre is in the picture: counted first, so that the list takes no
    // more memory than it holds (a Lytro-class raw has some 234,000).
    auto in_picture = [&](LensIndex lens, Vec2* centre_px) {
        const MicroimageCentre centre = microimage_centre_px(m, lens);
        *centre_px = Vec2{centre.u, centre.v};
        return centre.valid && centre.u >= -0.5 && centre.u < W - 0.5 && centre.v >= -0.5 && centre.v < H - 0.5;
    };
    for (int pass = 0; pass < 2; ++pass) {
        std::size_t count = 0;
        for (std::int64_t l = std::int64_t(l0); l <= std::int64_t(l1); ++l) {
            for (std::int64_t k = std::int64_t(k0); k <= std::int64_t(k1); ++k) {
                const LensIndex lens{k, l};
                Vec2 centre;
                if (!in_picture(lens, &centre))
                    continue;  // the lattice centre is not in the picture
                ++count;
                if (pass == 1) {
                    MicroimageTruth truth = MicroimageTruth();
                    truth.lens = lens;
                    out.push_back(truth);
                }
            }
        }
        if (pass == 0)
            out.reserve(count);
    }

    // Lenses measured so far (as the quarter lenses of the camera's symmetry).
    std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>> known;
    const Symmetry symmetry(m, light, options);
    // Refracting microlenses with manufacturing errors: the anchors are the ideal array's, and each
    // lens is interpolated where it sits, then corrected for its errors (correct_for_errors).
    PlenopticCamera ideal, ideal_light;
    const bool perturbed = options.error_anchor_step >= 4 && options.anchor_step >= 4 && m.array.errors &&
                           light.array.errors && m.array.microlens && refracting_shape(*m.array.microlens) != nullptr;
    if (perturbed) {
        ideal = m;
        ideal.array.errors = nullptr;
        ideal_light = light;
        ideal_light.array.errors = nullptr;
    }
    const PlenopticCamera& base = perturbed ? ideal : m;
    const PlenopticCamera& base_light = perturbed ? ideal_light : light;
    if (!interpolates(base, base_light, options) || out.empty()) {
        counts.measured = out.size();
        if (!measure_symmetric(m, light, options, out, 1, progress, cancelled, nullptr, &known))
            out.clear();
        counts.quarter_lenses = symmetry.valid() ? known.size() : 0;
        return out;
    }
    // Levels of anchors: anchor_step, then half of it, ... down to 4 lenses apart. At each level the
    // lenses not yet interpolated get the anchors they read (those not measured yet are measured),
    // and are interpolated where those vouch for the cubic; the rest go on to the next level (near
    // where the main lens begins to vignette, the light changes too fast for the coarser anchors).
    // The lenses left at the end are measured. Every decision depends on the lenses alone. The
    // anchors are measured in canonical.model() (the camera itself, or its array turned back onto
    // the axis: Canonical), the lenses left in the camera.
    const Canonical canonical(base, base_light, options);
    const PlenopticCamera& am = canonical.model();
    const Symmetry anchor_symmetry(am, canonical.light(), options);
    // A lens's displacement in the array's plane (perturbed: where the ideal lens it is sits).
    auto shift = [&](LensIndex lens) {
        if (!perturbed)
            return Vec2{0, 0};
        const LensError e = m.array.error_of(lens);
        return Vec2{e.dx_mm, e.dy_mm};
    };
    // Where each lens lies among the anchors; their range (X from range[0] to range[1], Y from
    // range[2] to range[3]).
    std::vector<Vec2> at(out.size());
    double range[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
    for (std::size_t i = 0; i < out.size(); ++i) {
        at[i] = canonical.position(out[i].lens, shift(out[i].lens));
        range[0] = std::min(range[0], at[i].x);
        range[1] = std::max(range[1], at[i].x);
        range[2] = std::min(range[2], at[i].y);
        range[3] = std::max(range[3], at[i].y);
    }
    // Quarter lenses measured as anchors in the canonical camera (`known` holds the camera's own).
    std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>> known_canonical;
    auto& anchor_known = canonical.active() ? known_canonical : known;
    const std::size_t total = out.size();
    std::unordered_map<std::uint64_t, AnchorValue> values;
    std::vector<std::size_t> pending(out.size());  // indices into `out` not yet found
    for (std::size_t i = 0; i < out.size(); ++i)
        pending[i] = i;
    // Progress: the anchors are the first half of the work, the lenses measured after them the rest.
    auto share = [&](std::size_t first) {
        return progress ? MicroimageProgress([&progress, first, total](std::size_t now, std::size_t count) {
            progress(first + now * (total / 4) / std::max<std::size_t>(1, count), total);
        })
                        : MicroimageProgress();
    };
    // Perturbed: whether each lens was interpolated between the anchors.
    std::vector<char> interpolated(perturbed ? out.size() : 0, 0);
    int level = 0;
    for (std::int64_t step = options.anchor_step; step >= 4 && !pending.empty(); step /= 2, ++level) {
        if (step % 2 != 0)
            break;
        Anchors anchors;
        anchors.values = &values;
        anchors.cover(step, range);
        if (!anchors.enough())
            break;  // fewer than five anchors a side
        // The anchors the pending lenses read that are not measured yet (sorted row by row below).
        std::vector<MicroimageTruth> measured =
            anchors.read_by(pending, at, [&](std::uint64_t key) { return values.count(key) != 0; });
        // Anchors that cost more than measuring the lenses they serve: measure those lenses. (What
        // a set of lenses costs: the lenses to measure for it, the quarter lenses with the symmetry.)
        auto cost = [&](const Symmetry& sym, const MicrolensArray& array,
                        const std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>>& done,
                        std::size_t count, const std::function<LensIndex(std::size_t)>& lens_at) {
            if (!sym.valid())
                return count;
            std::unordered_map<std::uint64_t, char> seen;
            for (std::size_t i = 0; i < count; ++i) {
                bool mirror_x, mirror_y;
                const std::uint64_t key = anchor_key(Symmetry::quarter_lens(array, lens_at(i), &mirror_x, &mirror_y));
                if (done.count(key) == 0)
                    seen.emplace(key, 1);
            }
            return seen.size();
        };
        if (4 * cost(anchor_symmetry, am.array, anchor_known, measured.size(),
                     [&](std::size_t i) { return measured[i].lens; }) >
            cost(symmetry, m.array, known, pending.size(), [&](std::size_t i) { return out[pending[i]].lens; }))
            break;
        sort_row_by_row(measured);
        std::vector<char> lobes;
        if (!measure_symmetric(am, canonical.light(), options, measured, step, share(std::min(level, 1) * total / 4),
                               cancelled, &lobes, &anchor_known)) {
            out.clear();
            return out;
        }
        counts.anchors += measured.size();
        for (std::size_t n = 0; n < measured.size(); ++n) {
            const MicroimageTruth& t = measured[n];
            const MicroimageCentre centre = microimage_centre_px(am, t.lens);
            AnchorValue value;
            value.lobe = lobes[n] != 0;
            value.lit = t.lit && centre.valid;
            value.value[0] = value.lit ? t.u_px - centre.u : 0;
            value.value[1] = value.lit ? t.v_px - centre.v : 0;
            value.value[2] = t.lit_fraction;
            values[anchor_key(t.lens)] = value;
        }
        // The lenses left, kept in place (the list is 8 bytes a lens of the picture at first).
        std::size_t left = 0;
        for (std::size_t index : pending) {
            Vec2 centre;
            if (!canonical.centre_px(out[index].lens, &centre, shift(out[index].lens)) ||
                !interpolate(anchors, at[index], &out[index], centre)) {
                pending[left++] = index;
                continue;
            }
            if (perturbed)
                interpolated[index] = 1;
            const Vec2 c = canonical.to_camera_px(Vec2{out[index].u_px, out[index].v_px});
            out[index].u_px = c.x;
            out[index].v_px = c.y;
        }
        pending.resize(left);
        pending.shrink_to_fit();
    }
    if (perturbed && counts.anchors > 0) {
        if (!correct_for_errors(light, canonical, anchor_symmetry, options, at, interpolated, range,
                                cancelled, out, pending, counts)) {
            out.clear();
            return out;
        }
    }
    counts.interpolated = out.size() - pending.size();
    counts.measured = pending.size();
    if (counts.anchors == 0) {
        // No level paid: every lens measured.
        if (!measure_symmetric(m, light, options, out, 1, progress, cancelled, nullptr, &known))
            out.clear();
        counts.quarter_lenses = symmetry.valid() ? known.size() : 0;
        return out;
    }
    std::vector<MicroimageTruth> measured(pending.size(), MicroimageTruth());
    for (std::size_t i = 0; i < pending.size(); ++i)
        measured[i].lens = out[pending[i]].lens;
    if (!measure_symmetric(m, light, options, measured, 1, share(total / 2), cancelled, nullptr, &known)) {
        out.clear();
        return out;
    }
    for (std::size_t i = 0; i < pending.size(); ++i)
        out[pending[i]] = measured[i];
    // (With errors the anchors' quarter lenses are the ideal array's, and the lenses left are measured
    // each where they are.)
    counts.quarter_lenses = canonical.active() || (perturbed && anchor_symmetry.valid())
                                ? anchor_known.size() + pending.size()
                                : (symmetry.valid() ? known.size() : 0);
    return out;
}

std::vector<MicroimageTruth> measured_microimages(const PlenopticCamera& m, const std::vector<LensIndex>& lenses,
                                                  const MicroimageOptions& options, const PlenopticCamera* through)
{
    std::vector<MicroimageTruth> out(lenses.size(), MicroimageTruth());
    for (std::size_t i = 0; i < lenses.size(); ++i)
        out[i].lens = lenses[i];
    if (m.array.grid == GridType::None || !m.lens)
        return std::vector<MicroimageTruth>();
    measure_symmetric(m, through ? *through : m, options, out, 1, MicroimageProgress(), MicroimageCancel(), nullptr,
                      nullptr);
    return out;
}

LatticeFit fit_microimage_lattice(const PlenopticCamera& m, const std::vector<MicroimageTruth>& truth)
{
    LatticeFit fit = LatticeFit();
    fit.valid = false;
    // Least squares on centred indices (k_s - mk, l - ml): the normal equations separate the mean.
    double mk = 0, ml = 0, mu = 0, mv = 0;
    std::size_t n = 0;
    for (const MicroimageTruth& t : truth) {
        if (!t.lit)
            continue;
        mk += double(skew_k(m.array.grid, t.lens));
        ml += double(t.lens.l);
        mu += t.u_px;
        mv += t.v_px;
        ++n;
    }
    if (n < 3)
        return fit;
    mk /= n;
    ml /= n;
    mu /= n;
    mv /= n;
    double skk = 0, skl = 0, sll = 0, sku = 0, slu = 0, skv = 0, slv = 0;
    for (const MicroimageTruth& t : truth) {
        if (!t.lit)
            continue;
        const double dk = double(skew_k(m.array.grid, t.lens)) - mk, dl = double(t.lens.l) - ml;
        skk += dk * dk;
        skl += dk * dl;
        sll += dl * dl;
        sku += dk * (t.u_px - mu);
        slu += dl * (t.u_px - mu);
        skv += dk * (t.v_px - mv);
        slv += dl * (t.v_px - mv);
    }
    const double det = skk * sll - skl * skl;
    if (!(det > 1e-9 * std::max(1.0, skk * sll)))
        return fit;  // all lit lenses in one row or one column
    fit.basis_a_px[0] = (sku * sll - slu * skl) / det;
    fit.basis_b_px[0] = (slu * skk - sku * skl) / det;
    fit.basis_a_px[1] = (skv * sll - slv * skl) / det;
    fit.basis_b_px[1] = (slv * skk - skv * skl) / det;
    fit.origin_px[0] = mu - fit.basis_a_px[0] * mk - fit.basis_b_px[0] * ml;
    fit.origin_px[1] = mv - fit.basis_a_px[1] * mk - fit.basis_b_px[1] * ml;
    fit.valid = true;
    fit.lenses = n;
    double sum2 = 0;
    for (const MicroimageTruth& t : truth) {
        if (!t.lit)
            continue;
        const double r = length(lattice_residual(m, fit, t));
        sum2 += r * r;
        if (r >= fit.max_residual_px) {
            fit.max_residual_px = r;
            fit.worst = t.lens;
        }
    }
    fit.rms_residual_px = std::sqrt(sum2 / n);
    return fit;
}

Vec2 lattice_residual(const PlenopticCamera& m, const LatticeFit& fit, const MicroimageTruth& lens)
{
    const double k = double(skew_k(m.array.grid, lens.lens)), l = double(lens.lens.l);
    return Vec2{lens.u_px - (fit.origin_px[0] + k * fit.basis_a_px[0] + l * fit.basis_b_px[0]),
                lens.v_px - (fit.origin_px[1] + k * fit.basis_a_px[1] + l * fit.basis_b_px[1])};
}

MicroimageSummary summarise_microimages(const PlenopticCamera& m, const std::vector<MicroimageTruth>& truth,
                                        const MicroimageOptions& options, const std::string& file)
{
    MicroimageSummary summary;
    summary.file = file;
    summary.lenses = truth.size();
    summary.lit_lenses = 0;
    summary.options = options;
    summary.lens_errors = m.array.errors != nullptr;
    summary.fit = fit_microimage_lattice(m, truth);
    double sum2 = 0, largest = 0;
    for (const MicroimageTruth& t : truth) {
        if (!t.lit)
            continue;
        const MicroimageCentre centre = microimage_centre_px(m, t.lens);
        if (!centre.valid)
            continue;
        const double u = centre.u, v = centre.v;
        ++summary.lit_lenses;
        const double r = std::hypot(t.u_px - u, t.v_px - v);
        sum2 += r * r;
        largest = std::max(largest, r);
    }
    summary.from_lattice_rms_px = summary.lit_lenses > 0 ? std::sqrt(sum2 / summary.lit_lenses) : NAN;
    summary.from_lattice_max_px = summary.lit_lenses > 0 ? largest : NAN;
    return summary;
}

namespace {

// The shortest "%.*g" that reads back to the same double.
std::string shortest(double value)
{
    char buffer[40];
    for (int digits = 1; digits <= 17; ++digits) {
        std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
        if (std::strtod(buffer, nullptr) == value)
            break;
    }
    return buffer;
}

} // namespace

std::string microimages_csv_header(const PlenopticCamera& m, bool per_channel)
{
    std::string out = "k,l,u,v,lit_fraction,residual_u,residual_v";
    out += per_channel ? ",u_r,v_r,u_g,v_g,u_b,v_b" : "";
    out += m.array.errors ? ",dx_mm,dy_mm,dz_mm,focal_length_mm,tilt_deg,tilt_azimuth_deg\n" : "\n";
    return out;
}

std::string microimages_csv_lines(const PlenopticCamera& m, const std::vector<MicroimageTruth>& truth,
                                  const LatticeFit& fit, const std::vector<std::vector<MicroimageTruth>>& channels,
                                  std::size_t begin, std::size_t end)
{
    const bool per_channel = channels.size() == 3;
    const bool errors = m.array.errors != nullptr;
    std::string out;
    for (std::size_t index = begin; index < end && index < truth.size(); ++index) {
        const MicroimageTruth& t = truth[index];
        out += std::to_string(static_cast<long long>(t.lens.k)) + "," + std::to_string(static_cast<long long>(t.lens.l));
        if (t.lit) {
            out += "," + shortest(t.u_px) + "," + shortest(t.v_px) + "," + shortest(t.lit_fraction);
            if (fit.valid) {
                const Vec2 r = lattice_residual(m, fit, t);
                out += "," + shortest(r.x) + "," + shortest(r.y);
            } else {
                out += ",,";
            }
        } else {
            out += ",,," + shortest(t.lit_fraction) + ",,";
        }
        for (std::size_t c = 0; per_channel && c < 3; ++c) {
            const MicroimageTruth& ct = channels[c][index];
            out += ct.lit ? "," + shortest(ct.u_px) + "," + shortest(ct.v_px) : ",,";
        }
        if (errors) {
            // The lens as it is (array/lens_errors.h): the columns a lens_table reads back.
            const LensError e = m.array.error_of(t.lens);
            out += "," + shortest(e.dx_mm) + "," + shortest(e.dy_mm) + "," + shortest(e.dz_mm) + ",";
            out += m.array.microlens->forms_image() ? shortest(m.array.focal_length_mm(t.lens)) : std::string();
            out += "," + shortest(e.tilt_deg) + "," + shortest(e.tilt_azimuth_deg);
        }
        out += "\n";
    }
    return out;
}

std::string microimages_csv(const PlenopticCamera& m, const std::vector<MicroimageTruth>& truth, const LatticeFit& fit,
                            const std::vector<std::vector<MicroimageTruth>>& channels)
{
    return microimages_csv_header(m, channels.size() == 3) +
           microimages_csv_lines(m, truth, fit, channels, 0, truth.size());
}

} // namespace plenoptic
