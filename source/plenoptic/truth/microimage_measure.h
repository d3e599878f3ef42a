// SPDX-License-Identifier: AGPL-3.0-or-later
// How the microimage truth (truth/microimages.h) measures a lens: its light in a white scene,
// traced through the renderer's own rays cell point by cell point, region by region; lenses in runs
// of neighbours; and the camera's mirror symmetry, where only a quarter of the lenses is measured.
// Shared by the truth's sources in truth/ (microimages, microimage_anchors, microimage_errors);
// not for other users.

#ifndef PLENOPTIC_MICROIMAGE_MEASURE_H
#define PLENOPTIC_MICROIMAGE_MEASURE_H

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/core/lattice.h"
#include "plenoptic/core/vec.h"
#include "plenoptic/truth/microimages.h"

namespace plenoptic {
namespace microimage_detail {

// Sensor pixel (centre convention, unbounded) of an optics-frame point projected from the exit
// pupil's centre onto the sensor plane.
bool project_to_sensor_px(const PlenopticCamera& m, Vec3 q, Vec2* px);

// The array-local box (x0, y0, x1, y1) that the picture's corners project to, or false.
bool picture_on_array(const PlenopticCamera& m, double box[4]);

// A point of the lens's cell at which its light is measured, as the renderer's aperture sample
// (lens_u, lens_v), and the share of the cell it stands for (1 / divisor).
struct CellNode {
    double lens_u, lens_v, divisor;
};

// One lens's microimage measured through `light`'s rays (its lens and start points `m`'s), cell
// point by cell point, each region's radii sought near a prediction where there is one.
class LensMeasurer {
public:
    // Per cell point, the radii of its region in the last kHistory lenses measured with it, newest
    // first (fewer at a run's start or after a lens without that region), and a prediction.
    struct Radii {
        std::vector<std::vector<std::vector<double>>> history;
        std::vector<double> predicted, now;
    };
    static const std::size_t kHistory = 2;

    LensMeasurer(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options);

    // Radii with no history, for this measurer's cell points.
    Radii fresh() const
    {
        Radii radii;
        radii.history.resize(all_nodes_.size());
        return radii;
    }

    // Measures truth.lens; `radii` (if given) predicts each region from its history and takes this
    // lens's radii into it; `own_nodes` is scratch. `lobe_out` (if given): whether a region of the
    // microimage is a lobe of light that crossed cells (region_moments).
    void measure(MicroimageTruth& truth, Radii* radii, std::vector<CellNode>* own_nodes, bool* lobe_out) const;

private:
    const PlenopticCamera& m_;
    const PlenopticCamera& light_;
    const MicroimageOptions& options_;
    const std::vector<CellNode> all_nodes_;
    const bool cut_cells_;
};

// Measures the lenses of `out` (their `lens` set, row by row), each through `light`'s rays; a run
// of neighbours is lenses k, k + step, k + 2 step, ... of one row. Reports (now, out.size()) about
// every tenth of the lenses; false when `cancelled` stopped it. `lobes` (if given): per lens,
// whether a region of its microimage is a lobe of light that crossed cells (region_moments).
bool measure_lenses(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options,
                    std::vector<MicroimageTruth>& out, std::int64_t step, const MicroimageProgress& progress,
                    const MicroimageCancel& cancelled, std::vector<char>* lobes = nullptr);

// The camera's symmetry about its optical axis, where the truth uses it: refracting microlenses (the
// costly ones, measured at refracting_points^2 cell points) on an ideal array (no manufacturing
// errors, not tilted, one kind of lens) whose lens (0, 0) sits on the axis, on a hexagonal or square
// lattice, its rows along the sensor's x or y axis. The main lens is symmetric about its axis (every
// model is), and so are the sensor's and the array's planes; the lattice with its cells is symmetric
// under the mirrors in the array's x and y axes through lens (0, 0). Each mirror maps the camera
// onto itself, lens onto lens, and the light through a lens onto the light through its image; and
// the truth's own rule is symmetric
// under the same mirrors (its cell points, the renderer's map of the cell, and its directions from
// the start point, 0 and 90 degrees among them; its start point is the mirrored guess, or the
// centroid of a coarse grid centred on it). So a lens's microimage is its mirror image's, mirrored:
// only the lenses of the quarter x >= 0, y >= 0 of the array's frame are measured, and every other
// lens takes the microimage of its image there, mirrored (centroid; the lit fraction as it is). The
// lattice's turns by 60 degrees and its mirrors in lines between the axes are symmetries of the
// camera too, but not of the rule (a lens and its image under them, each measured, differ by the
// rule's own error, some 1e-3 px): used, they would put steps of that size into the truth where a
// lens and its neighbour would take their microimages from lenses measured apart.
class Symmetry {
public:
    Symmetry(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options)
    {
        const MicrolensArray& a = m.array;
        valid_ = options.symmetry && a.microlens && a.microlens->forms_image() && !a.microlens->first_order_exact() &&
                 !a.errors && !light.array.errors &&
                 (a.grid == GridType::Hexagonal || a.grid == GridType::Rectangular) && !a.pose.tilted &&
                 !light.array.pose.tilted && a.lens_type_count == 1 && a.pose.centre_mm.x == 0 &&
                 a.pose.centre_mm.y == 0 && light.array.pose.centre_mm.x == 0 && light.array.pose.centre_mm.y == 0;
        // The array's turn about the axis (its rows' direction in the optics frame): a multiple of 90
        // degrees (exact: array/microlens_array.h), so that its mirrors are the sensor's, under which
        // the rule's coarse grids and directions, laid out in pixels, are symmetric too.
        const Vec3 x = mul(a.pose.rotation, Vec3{1, 0, 0});
        frame_[0] = x.x;
        frame_[1] = x.y;
        valid_ = valid_ && (frame_[0] == 0 || frame_[1] == 0);
    }
    bool valid() const { return valid_; }

    // The lens of the quarter x >= 0, y >= 0 whose mirror image `lens` is, and the mirrors that map
    // it there (x -> -x, y -> -y).
    static LensIndex quarter_lens(const MicrolensArray& a, LensIndex lens, bool* mirror_x, bool* mirror_y)
    {
        const Vec2 c = a.lattice_centre_local(lens);
        *mirror_x = c.x < 0;
        *mirror_y = c.y < 0;
        if (!*mirror_x && !*mirror_y)
            return lens;
        return a.nearest(std::fabs(c.x), std::fabs(c.y));  // a lattice point: the lattice is symmetric
    }

    // A sensor point (centre-convention pixels) of the quarter lens's microimage, mirrored.
    Vec2 map_px(const Sensor& sensor, bool mirror_x, bool mirror_y, Vec2 px) const
    {
        const Vec3 p = sensor.point(px.x + 0.5, px.y + 0.5);
        // Into the array's frame (a turn about the axis), mirrored, and back.
        Vec2 q{frame_[0] * p.x + frame_[1] * p.y, -frame_[1] * p.x + frame_[0] * p.y};
        if (mirror_x)
            q.x = -q.x;
        if (mirror_y)
            q.y = -q.y;
        const PixelPoint out = sensor.to_pixel(frame_[0] * q.x - frame_[1] * q.y, frame_[1] * q.x + frame_[0] * q.y);
        return Vec2{out.u, out.v};
    }

private:
    bool valid_ = false;
    double frame_[2] = {1, 0};  // cos, sin of the array's turn
};

// A lens as a key of the maps of measured lenses.
inline std::uint64_t anchor_key(LensIndex lens)
{
    return (std::uint64_t(lens.k) << 32) ^ (std::uint64_t(lens.l) & 0xffffffffull);
}

// Lenses in the order measure_lenses takes them: row by row (l, then k, increasing).
void sort_row_by_row(std::vector<MicroimageTruth>& lenses);

// measure_lenses, with the camera's symmetry where it holds: each lens of `out` takes the microimage
// of its quarter lens, those measured once each (and kept in `cache`, by lens, for later calls).
bool measure_symmetric(const PlenopticCamera& m, const PlenopticCamera& light, const MicroimageOptions& options,
                       std::vector<MicroimageTruth>& out, std::int64_t step, const MicroimageProgress& progress,
                       const MicroimageCancel& cancelled, std::vector<char>* lobes,
                       std::unordered_map<std::uint64_t, std::pair<MicroimageTruth, char>>* cache);

} // namespace microimage_detail
} // namespace plenoptic

#endif
