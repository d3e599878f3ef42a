// SPDX-License-Identifier: AGPL-3.0-or-later
// Refracting lenses with manufacturing errors, corrected from Jacobian anchors (see the header).

#include "plenoptic/truth/microimage_errors.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <memory>
#include <string>

#include "plenoptic/array/lens_errors.h"
#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/core/threads.h"

namespace plenoptic {
namespace microimage_detail {

namespace {

// The corrections' cubic is used where its estimated error is below these. The differences carry
// the measurements' own scatter (some 1e-4 to 1e-3 px, 3e-5 of lit fraction, BENCHMARKS "Refracting
// microlenses between anchors") divided by the step, and their fourth differences mostly that
// scatter: a bound at the anchors' 5e-4 px would refuse most lenses on it alone.
const double kCorrectionPx = 2e-3;
const double kCorrectionFraction = 2e-4;

// One error parameter of a lens, and the step of its differences.
struct ErrorParameter {
    // 0: dz (mm); 1: focal factor - 1; 2, 3: the axis's x, y; 4 + 2 a + c: the displacement of the
    // lens's adjacent lens a (adjacent_lenses' order: the same lattice direction for every lens)
    // from its own, component c (x, y; mm, array frame).
    int kind;
    double step;
};

// The parameters' largest count: four of the lens's own, two for each of up to eight adjacent lenses.
const int kMaxErrorParameters = 4 + 2 * 8;

// The lens's own error with parameter `kind` (< 4) at `value` and no other.
LensError error_with(int kind, double value)
{
    LensError e;
    if (kind == 0) {
        e.dz_mm = value;
    } else if (kind == 1) {
        e.focal_factor = 1 + value;
    } else {
        e.tilt_deg = std::asin(std::fabs(value)) * 180 / kPi;
        e.tilt_azimuth_deg = (kind == 2 ? 0 : 90) + (value < 0 ? 180 : 0);
    }
    return e;
}

// The lens's parameters' values, in `parameters`' order.
void error_values(const MicrolensArray& a, LensIndex lens, const std::vector<ErrorParameter>& parameters, double* x)
{
    const LensError e = a.error_of(lens);
    LensIndex adjacent[8];
    const int count = adjacent_lenses(a.grid, lens, adjacent);
    for (std::size_t p = 0; p < parameters.size(); ++p) {
        const int kind = parameters[p].kind;
        if (kind == 0) {
            x[p] = e.dz_mm;
        } else if (kind == 1) {
            x[p] = e.focal_factor - 1;
        } else if (kind < 4) {
            x[p] = kind == 2 ? e.axis.x : e.axis.y;
        } else {
            const int j = (kind - 4) / 2;
            const LensError n = j < count ? a.error_of(adjacent[j]) : e;
            x[p] = (kind - 4) % 2 == 0 ? n.dx_mm - e.dx_mm : n.dy_mm - e.dy_mm;
        }
    }
}

// The linear part of an affine map of sensor points (pixels): a vector's image.
template <class F> Vec2 linear_part(const F& map, Vec2 d)
{
    const Vec2 o = map(Vec2{0, 0}), p = map(d);
    return Vec2{p.x - o.x, p.y - o.y};
}

// The parameters the errors give a lens, each with the step of its differences: the largest value
// the errors give it (a lens's own displacement for a neighbour's relative one, per component).
std::vector<ErrorParameter> error_parameters(const LensErrors& errors, GridType grid)
{
    std::vector<ErrorParameter> parameters;
    if (errors.max_dz_mm() > 0)
        parameters.push_back(ErrorParameter{0, errors.max_dz_mm()});
    if (errors.max_focal_deviation() > 0)
        parameters.push_back(ErrorParameter{1, errors.max_focal_deviation()});
    if (errors.tilts()) {
        const double h = std::sin(errors.max_tilt_deg() * kPi / 180);
        parameters.push_back(ErrorParameter{2, h});
        parameters.push_back(ErrorParameter{3, h});
    }
    if (errors.max_shift_mm() > 0) {
        LensIndex adjacent[8];
        const int count = adjacent_lenses(grid, LensIndex{0, 0}, adjacent);
        for (int c = 0; c < 2 * count; ++c)
            parameters.push_back(ErrorParameter{4 + c, errors.max_shift_mm() / std::sqrt(2.0)});
    }
    return parameters;
}

// A perturbation of the Jacobian anchors: parameter `kind` at `value`, the lens's focal factor less 1
// at `focal` (besides that parameter's own).
struct Perturbation {
    int kind;
    double value, focal;
};

// The table of errors that perturbs each of `lenses` alike (each alone in its neighbourhood: the
// anchors lie far apart); lenses of the type's focal length `type_focal`.
std::shared_ptr<const LensErrors> perturbation_table(const Perturbation& pert, const std::vector<MicroimageTruth>& lenses,
                                                     GridType grid, double type_focal)
{
    std::vector<LensTableRow> rows;
    for (const MicroimageTruth& lens : lenses) {
        LensTableRow own;
        own.lens = lens.lens;
        own.error = pert.kind < 4 ? error_with(pert.kind, pert.value) : LensError();
        if (pert.focal != 0)
            own.error.focal_factor = 1 + pert.focal;
        if (pert.kind < 4 || pert.focal != 0)
            rows.push_back(own);
        if (pert.kind >= 4) {
            LensIndex adjacent[8];
            adjacent_lenses(grid, lens.lens, adjacent);
            LensTableRow next;
            next.lens = adjacent[(pert.kind - 4) / 2];
            ((pert.kind - 4) % 2 == 0 ? next.error.dx_mm : next.error.dy_mm) = pert.value;
            rows.push_back(next);
        }
    }
    return LensErrors::tabled(rows, std::string(), &type_focal, 1);
}

// The differences of `lens` (an anchor of the Jacobian) from those of its quarter lens `quarter`,
// measured (`from`), under the mirrors that map it there: each parameter mirrored (the axis's and
// the displacements' components along a mirror change sign, an adjacent lens is its mirror
// image's), each sensor vector mirrored. False when the adjacent lenses do not match.
bool mirror_differences(const PlenopticCamera& am, const Symmetry& symmetry,
                        const std::vector<ErrorParameter>& parameters, LensIndex lens, LensIndex quarter,
                        bool mirror_x, bool mirror_y, const std::vector<double>& from, std::vector<double>* out)
{
    // The anchor's adjacent lens a is the mirror image of the quarter lens's adjacent[image[a]].
    LensIndex adjacent[8], quarter_adjacent[8];
    const int count = adjacent_lenses(am.array.grid, lens, adjacent);
    adjacent_lenses(am.array.grid, quarter, quarter_adjacent);
    int image[8];
    bool matched = true;
    for (int a = 0; a < count; ++a) {
        const Vec2 o = am.array.lattice_centre_local(adjacent[a]) - am.array.lattice_centre_local(lens);
        const Vec2 want{mirror_x ? -o.x : o.x, mirror_y ? -o.y : o.y};
        image[a] = -1;
        for (int b = 0; b < count; ++b) {
            const Vec2 ob =
                am.array.lattice_centre_local(quarter_adjacent[b]) - am.array.lattice_centre_local(quarter);
            if (std::fabs(ob.x - want.x) + std::fabs(ob.y - want.y) < 1e-6 * am.array.pitch_mm)
                image[a] = b;
        }
        matched = matched && image[a] >= 0;
    }
    if (!matched)
        return false;
    const std::size_t P = parameters.size();
    std::vector<double>& to = *out;
    to.assign(9 * P, 0.0);
    for (std::size_t p = 0; p < P; ++p) {
        const int kind = parameters[p].kind;
        int source_kind = kind;
        double sign = 1;
        if (kind == 2 && mirror_x)
            sign = -1;
        if (kind == 3 && mirror_y)
            sign = -1;
        if (kind >= 4) {
            const int a = (kind - 4) / 2, c = (kind - 4) % 2;
            source_kind = 4 + 2 * image[a] + c;
            if ((c == 0 && mirror_x) || (c == 1 && mirror_y))
                sign = -1;
        }
        std::size_t source = P;
        for (std::size_t r = 0; r < P; ++r)
            if (parameters[r].kind == source_kind)
                source = r;
        for (int order = 0; order < 3; ++order) {  // J, H, K: J and K change sign with the parameter
            const double* f = &from[9 * source + 3 * order];
            double* t = &to[9 * p + 3 * order];
            const double factor = order == 1 ? 1 : sign;
            const Vec2 d = linear_part(
                [&](Vec2 px) { return symmetry.map_px(am.sensor, mirror_x, mirror_y, px); },
                Vec2{factor * f[0], factor * f[1]});
            t[0] = d.x;
            t[1] = d.y;
            t[2] = factor * f[2];
        }
    }
    return true;
}

// The perturbations the Jacobian anchors are measured with: each parameter at +h and -h alone
// (side(p, 0), side(p, 1)) and, when the errors scale focal lengths, each other parameter at +h with
// the focal factor's +step and -step (mixed(p, 0), mixed(p, 1)).
class Perturbations {
public:
    explicit Perturbations(const std::vector<ErrorParameter>& parameters)
        : P_(parameters.size()), focal_(parameters.size()), side_(P_), mixed_(P_)
    {
        for (std::size_t p = 0; p < P_; ++p)
            if (parameters[p].kind == 1)
                focal_ = p;
        for (std::size_t p = 0; p < P_; ++p)
            for (int s = 0; s < 2; ++s) {
                const double sign = s == 0 ? 1 : -1;
                side_[p][s] = list_.size();
                list_.push_back(Perturbation{parameters[p].kind, sign * parameters[p].step, 0});
                if (mixes(p)) {
                    mixed_[p][s] = list_.size();
                    list_.push_back(Perturbation{parameters[p].kind, parameters[p].step, sign * parameters[focal_].step});
                }
            }
        // A measurement's search is seeded from one a step away: the ideal lens's (size()), or for a
        // mixed perturbation the focal factor's step alone.
        seeded_from_.assign(list_.size(), list_.size());
        seeds_others_.assign(list_.size(), 0);
        for (std::size_t p = 0; p < P_; ++p)
            for (int s = 0; s < 2 && mixes(p); ++s) {
                seeded_from_[mixed_[p][s]] = side_[focal_][s];
                seeds_others_[side_[focal_][s]] = 1;
            }
    }

    std::size_t size() const { return list_.size(); }
    const Perturbation& operator[](std::size_t n) const { return list_[n]; }
    // The focal factor's parameter (the parameters' count when the errors have none).
    std::size_t focal() const { return focal_; }
    bool mixes(std::size_t p) const { return focal_ < P_ && p != focal_; }
    std::size_t side(std::size_t p, int s) const { return side_[p][s]; }
    std::size_t mixed(std::size_t p, int s) const { return mixed_[p][s]; }
    std::size_t seeded_from(std::size_t n) const { return seeded_from_[n]; }
    bool seeds_others(std::size_t n) const { return seeds_others_[n] != 0; }

private:
    std::size_t P_, focal_;
    std::vector<Perturbation> list_;
    std::vector<std::array<std::size_t, 2>> side_, mixed_;
    std::vector<std::size_t> seeded_from_;
    std::vector<char> seeds_others_;
};

// An anchor of the Jacobian and the quarter lens it is measured as (Symmetry: its own lens where the
// mirror symmetry does not hold).
struct Mirrored {
    std::size_t quarter;  // into the quarter lenses
    bool mirror_x, mirror_y;
};

// The anchors' quarter lenses, each once, and for each anchor its quarter lens and mirrors.
std::vector<MicroimageTruth> quarter_lenses(const PlenopticCamera& am, const Symmetry& symmetry,
                                            const std::vector<MicroimageTruth>& anchors, std::vector<Mirrored>* mirrored)
{
    mirrored->assign(anchors.size(), Mirrored());
    std::vector<MicroimageTruth> quarters;
    std::unordered_map<std::uint64_t, std::size_t> where;
    std::vector<LensIndex> of(anchors.size());
    for (std::size_t i = 0; i < anchors.size(); ++i) {
        Mirrored& mm = (*mirrored)[i];
        mm.mirror_x = mm.mirror_y = false;
        of[i] = symmetry.valid() ? Symmetry::quarter_lens(am.array, anchors[i].lens, &mm.mirror_x, &mm.mirror_y)
                                 : anchors[i].lens;
        if (where.emplace(anchor_key(of[i]), 0).second) {
            MicroimageTruth t = MicroimageTruth();
            t.lens = of[i];
            quarters.push_back(t);
        }
    }
    for (std::size_t n = 0; n < quarters.size(); ++n)
        where[anchor_key(quarters[n].lens)] = n;
    for (std::size_t i = 0; i < anchors.size(); ++i)
        (*mirrored)[i].quarter = where.at(anchor_key(of[i]));
    return quarters;
}

// Each quarter lens measured ideal from scratch (`ideal`), then with each perturbation
// (`measured[n]`, in a camera with its perturbation_table), each region's radii sought near a
// measurement of the same lens that differs from it by one small step: the ideal lens's, or for a
// mixed perturbation (a parameter with the focal factor's step) the focal factor's step alone (a
// step moves a boundary by a few hundredths of a pixel where it acts, and most not at all). The
// answer is the grid step that holds the crossing, as from scratch (boundary_on_grid); only the
// search is shorter (behind the 22 mm wide-angle about half the probes from scratch; the coarse
// search about dark start points, a third of those, is as long). On every thread, a quarter lens at
// a time; each result depends on the lens alone. False when cancelled.
bool measure_perturbed(const Canonical& canonical, const Perturbations& perturbations,
                       const std::vector<MicroimageTruth>& quarters, const MicroimageOptions& options,
                       const MicroimageCancel& cancelled, std::vector<MicroimageTruth>* ideal,
                       std::vector<std::vector<MicroimageTruth>>* measured)
{
    const PlenopticCamera& am = canonical.model();
    const std::size_t N = perturbations.size();
    const double type_focal = am.array.microlens->focal_length_mm(0);
    std::vector<PlenopticCamera> perturbed_model(N, am), perturbed_light(N, canonical.light());
    for (std::size_t n = 0; n < N; ++n) {
        const std::shared_ptr<const LensErrors> table =
            perturbation_table(perturbations[n], quarters, am.array.grid, type_focal);
        perturbed_model[n].array.errors = table;
        perturbed_light[n].array.errors = table;
    }
    const LensMeasurer ideal_measurer(am, canonical.light(), options);
    std::vector<LensMeasurer> measurers;
    measurers.reserve(N);
    for (std::size_t n = 0; n < N; ++n)
        measurers.emplace_back(perturbed_model[n], perturbed_light[n], options);
    *ideal = quarters;
    measured->assign(N, quarters);
    typedef std::vector<std::vector<std::vector<double>>> History;
    // A measurement's radii as a seed: each region's newest radii alone (a history of one lens
    // predicts that lens's radii, not a trend).
    auto newest = [](const History& history) {
        History seed(history.size());
        for (std::size_t point = 0; point < history.size(); ++point)
            if (!history[point].empty())
                seed[point].push_back(history[point][0]);
        return seed;
    };
    std::atomic<std::size_t> next(0);
    std::atomic<bool> stop(false);
    run_on_threads(thread_count(options.threads, quarters.size()), [&](int t) {
        const bool polls = t == 0;
        std::vector<CellNode> own_nodes;
        std::vector<History> seeds(N + 1);
        for (std::size_t i = next++; i < quarters.size() && !stop; i = next++) {
            LensMeasurer::Radii radii = ideal_measurer.fresh();
            ideal_measurer.measure((*ideal)[i], &radii, &own_nodes, nullptr);
            seeds[N] = newest(radii.history);
            // The seeds of others first.
            for (int pass = 0; pass < 2; ++pass)
                for (std::size_t n = 0; n < N && !stop; ++n) {
                    if ((perturbations.seeded_from(n) == N) != (pass == 0))
                        continue;
                    if (polls && cancelled && cancelled()) {
                        stop = true;
                        break;
                    }
                    radii.history = seeds[perturbations.seeded_from(n)];
                    measurers[n].measure((*measured)[n][i], &radii, &own_nodes, nullptr);
                    if (perturbations.seeds_others(n))
                        seeds[n] = newest(radii.history);
                }
        }
    });
    return !stop;
}

// Per quarter lens, for each parameter and each of du, dv and the lit fraction: J, H, and K (the
// mixed difference with the focal factor: a lens's light near its cell's edge, where its neighbours
// act, moves with its own focal length, some 9 % of the neighbours' effect a per cent of focal
// length behind the 22 mm wide-angle), 9 values a parameter. `valid[i]` is cleared where a
// measurement found no light.
std::vector<std::vector<double>> quarter_differences(const PlenopticCamera& am,
                                                     const std::vector<ErrorParameter>& parameters,
                                                     const Perturbations& perturbations,
                                                     const std::vector<MicroimageTruth>& quarters,
                                                     const std::vector<MicroimageTruth>& ideal,
                                                     const std::vector<std::vector<MicroimageTruth>>& measured,
                                                     std::vector<char>* valid)
{
    const std::size_t P = parameters.size(), focal = perturbations.focal();
    valid->assign(quarters.size(), 1);
    std::vector<std::vector<double>> jh(quarters.size(), std::vector<double>(9 * P, 0.0));
    auto value = [&](const MicroimageTruth& t, const MicroimageCentre& c, int q) {
        return q == 0 ? t.u_px - c.u : q == 1 ? t.v_px - c.v : t.lit_fraction;
    };
    const std::vector<MicroimageTruth>* focal_side[2] = {nullptr, nullptr};
    if (focal < P)
        for (int s = 0; s < 2; ++s)
            focal_side[s] = &measured[perturbations.side(focal, s)];
    for (std::size_t p = 0; p < P; ++p) {
        const double h = parameters[p].step;
        const std::vector<MicroimageTruth>* up = &measured[perturbations.side(p, 0)];
        const std::vector<MicroimageTruth>* down = &measured[perturbations.side(p, 1)];
        const bool mixes = perturbations.mixes(p);
        for (std::size_t i = 0; i < quarters.size(); ++i) {
            const MicroimageCentre c = microimage_centre_px(am, quarters[i].lens);
            bool lit = c.valid && (*up)[i].lit && ideal[i].lit && (*down)[i].lit;
            for (int s = 0; s < 2 && mixes; ++s)
                lit = lit && measured[perturbations.mixed(p, s)][i].lit && (*focal_side[s])[i].lit;
            if (!lit) {
                (*valid)[i] = 0;
                continue;
            }
            for (int q = 0; q < 3; ++q) {
                const double u = value((*up)[i], c, q), mid = value(ideal[i], c, q), d = value((*down)[i], c, q);
                jh[i][9 * p + q] = (u - d) / (2 * h);
                jh[i][9 * p + 3 + q] = (u - 2 * mid + d) / (h * h);
                if (mixes)
                    jh[i][9 * p + 6 + q] = (value(measured[perturbations.mixed(p, 0)][i], c, q) -
                                            value(measured[perturbations.mixed(p, 1)][i], c, q) -
                                            value((*focal_side[0])[i], c, q) + value((*focal_side[1])[i], c, q)) /
                                           (2 * parameters[focal].step * h);
            }
        }
    }
    return jh;
}

// Each anchor's differences, from its quarter lens's (mirror_differences), by anchor_key; anchors
// whose quarter lens is not valid are left out.
std::unordered_map<std::uint64_t, std::vector<double>>
anchor_differences(const PlenopticCamera& am, const Symmetry& symmetry, const std::vector<ErrorParameter>& parameters,
                   const std::vector<MicroimageTruth>& anchors, const std::vector<Mirrored>& mirrored,
                   const std::vector<MicroimageTruth>& quarters, const std::vector<char>& valid,
                   const std::vector<std::vector<double>>& jh)
{
    std::unordered_map<std::uint64_t, std::vector<double>> differences;
    for (std::size_t i = 0; i < anchors.size(); ++i) {
        const Mirrored& mm = mirrored[i];
        if (!valid[mm.quarter])
            continue;
        const std::vector<double>& from = jh[mm.quarter];
        if (!mm.mirror_x && !mm.mirror_y) {
            differences[anchor_key(anchors[i].lens)] = from;
            continue;
        }
        std::vector<double> to;
        if (mirror_differences(am, symmetry, parameters, anchors[i].lens, quarters[mm.quarter].lens, mm.mirror_x,
                               mm.mirror_y, from, &to))
            differences[anchor_key(anchors[i].lens)].swap(to);
    }
    return differences;
}

// Each lens of `lenses` (indices into `out`) corrected by the cubic through the 4 x 4 Jacobian
// anchors nearest it, for its own parameters' values, where their fourth differences vouch for it;
// `measure[index]` is set for the others. On every thread (each result depends on the lens alone).
void apply_corrections(const PlenopticCamera& light, const Canonical& canonical, const MicroimageOptions& options,
                       const std::vector<ErrorParameter>& parameters, std::size_t focal, const Anchors& jacobian,
                       const std::unordered_map<std::uint64_t, std::vector<double>>& differences,
                       const std::vector<std::size_t>& lenses, const std::vector<Vec2>& at,
                       std::vector<MicroimageTruth>& out, std::vector<char>* measure)
{
    const std::size_t P = parameters.size();
    std::atomic<std::size_t> next(0);
    const std::size_t kChunk = 256;
    run_on_threads(thread_count(options.threads, (lenses.size() + kChunk - 1) / kChunk), [&](int) {
        for (std::size_t first = next.fetch_add(kChunk); first < lenses.size(); first = next.fetch_add(kChunk))
            for (std::size_t n = first; n < std::min(lenses.size(), first + kChunk); ++n) {
                const std::size_t index = lenses[n];
                MicroimageTruth& truth = out[index];
                std::int64_t i0, j0;
                double x, y;
                jacobian.stencil(at[index], &i0, &j0, &x, &y);
                const std::vector<double>* block[6][6] = {};
                bool missing = false;
                jacobian.each(i0, j0, [&](std::int64_t i, std::int64_t j) {
                    const auto found = differences.find(anchor_key(jacobian.lens(i, j)));
                    if (found == differences.end())
                        missing = true;
                    else
                        block[j - j0 + 1][i - i0 + 1] = &found->second;
                });
                if (missing) {
                    (*measure)[index] = 1;
                    continue;
                }
                double xs[kMaxErrorParameters];
                error_values(light.array, truth.lens, parameters, xs);
                auto v = [&](std::int64_t i, std::int64_t j, int q) {
                    const std::vector<double>& d = *block[j - j0 + 1][i - i0 + 1];
                    double sum = 0;
                    const double xf = focal < P ? xs[focal] : 0;
                    for (std::size_t p = 0; p < P; ++p)
                        sum += d[9 * p + q] * xs[p] + 0.5 * d[9 * p + 3 + q] * xs[p] * xs[p] +
                               d[9 * p + 6 + q] * xs[p] * xf;
                    return sum;
                };
                const double allowed[3] = {kCorrectionPx, kCorrectionPx, kCorrectionFraction};
                double result[3];
                bool vouched = true;
                for (int q = 0; q < 3 && vouched; ++q) {
                    double error;
                    result[q] = cubic_through(jacobian, i0, j0, x, y, v, q, &error);
                    vouched = error <= allowed[q];
                }
                if (!vouched) {
                    (*measure)[index] = 1;
                    continue;
                }
                const Vec2 d =
                    linear_part([&](Vec2 px) { return canonical.to_camera_px(px); }, Vec2{result[0], result[1]});
                truth.u_px += d.x;
                truth.v_px += d.y;
                truth.lit_fraction += result[2];
            }
    });
}

} // namespace

bool correct_for_errors(const PlenopticCamera& light, const Canonical& canonical, const Symmetry& symmetry,
                        const MicroimageOptions& options,
                        const std::vector<Vec2>& at, const std::vector<char>& interpolated, const double range[4],
                        const MicroimageCancel& cancelled, std::vector<MicroimageTruth>& out,
                        std::vector<std::size_t>& pending, MicroimageWork& counts)
{
    const PlenopticCamera& am = canonical.model();
    const std::vector<ErrorParameter> parameters = error_parameters(*light.array.errors, am.array.grid);
    std::vector<std::size_t> lenses;  // the interpolated lenses
    for (std::size_t i = 0; i < out.size(); ++i)
        if (interpolated[i])
            lenses.push_back(i);
    if (parameters.empty() || lenses.empty())
        return true;

    // The Jacobian anchors: error_anchor_step lenses apart (at least five a side, else every lens is
    // measured).
    Anchors jacobian;
    jacobian.cover(options.error_anchor_step, range);
    std::vector<MicroimageTruth> anchors;
    if (jacobian.enough())
        anchors = jacobian.read_by(lenses, at, [](std::uint64_t) { return false; });
    if (anchors.empty()) {
        pending.insert(pending.end(), lenses.begin(), lenses.end());
        std::sort(pending.begin(), pending.end());
        return true;
    }
    // Where the camera's mirror symmetry holds (Symmetry), only the anchors' quarter lenses are
    // measured: a lens's microimage is its quarter lens's mirrored, with each parameter mirrored too
    // (the axis's and the displacements' components along a mirror change sign, an adjacent lens is
    // its mirror image's).
    std::vector<Mirrored> mirrored;
    const std::vector<MicroimageTruth> quarters = quarter_lenses(am, symmetry, anchors, &mirrored);
    const Perturbations perturbations(parameters);
    std::vector<MicroimageTruth> ideal;
    std::vector<std::vector<MicroimageTruth>> measured;
    if (!measure_perturbed(canonical, perturbations, quarters, options, cancelled, &ideal, &measured))
        return false;
    std::vector<char> valid;
    const std::vector<std::vector<double>> jh =
        quarter_differences(am, parameters, perturbations, quarters, ideal, measured, &valid);
    const std::unordered_map<std::uint64_t, std::vector<double>> differences =
        anchor_differences(am, symmetry, parameters, anchors, mirrored, quarters, valid, jh);
    counts.error_anchors = quarters.size();

    std::vector<char> measure(out.size(), 0);
    apply_corrections(light, canonical, options, parameters, perturbations.focal(), jacobian, differences, lenses, at,
                      out, &measure);
    std::size_t corrected = 0;
    for (std::size_t index : lenses) {
        if (measure[index])
            pending.push_back(index);
        else
            ++corrected;
    }
    std::sort(pending.begin(), pending.end());
    counts.corrected = corrected;
    return true;
}

} // namespace microimage_detail
} // namespace plenoptic
