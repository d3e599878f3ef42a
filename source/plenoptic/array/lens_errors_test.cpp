// SPDX-License-Identifier: AGPL-3.0-or-later
// Tests of microlens manufacturing errors against answers worked out here: the statistics of the
// truncated normal and of a uniform cap, the thin-lens definition of a tilted lens's focal point,
// brute-force nearest centres, the area of a scaled cell, and the lens table's rows as written.

#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "plenoptic/array/array_params.h"
#include "plenoptic/array/lens_errors.h"
#include "plenoptic/array/microlens_array.h"

namespace plenoptic {
namespace {

ArrayParams thin_array(GridType grid, double pitch, double f)
{
    ArrayParams a;
    a.given = true;
    a.grid = grid;
    a.has_pitch = true;
    a.pitch_mm = pitch;
    a.has_lens = true;
    a.lens = MicrolensType::ThinLens;
    a.focal_length_count = 1;
    a.focal_lengths_mm[0] = f;
    a.has_distance = true;
    a.distance_mm = f;
    return a;
}

ErrorSpec spec(double s, double sz, double f, double r, std::int64_t seed)
{
    ErrorSpec e;
    e.position_sd_mm = s;
    e.position_sd_z_mm = sz;
    e.focal_sd = f;
    e.rotation_deg = r;
    e.seed = seed;
    return e;
}

struct Moments {
    double mean = 0, sd = 0, largest = 0;
};

Moments moments(const std::vector<double>& x)
{
    Moments m;
    for (double v : x)
        m.mean += v;
    m.mean /= double(x.size());
    for (double v : x) {
        m.sd += (v - m.mean) * (v - m.mean);
        m.largest = std::max(m.largest, std::fabs(v));
    }
    m.sd = std::sqrt(m.sd / double(x.size() - 1));
    return m;
}

// Standard deviation of a standard normal cut at +-a: 1 - 2 a phi(a) / (2 Phi(a) - 1).
double truncated_sd(double a)
{
    const double phi = std::exp(-0.5 * a * a) / std::sqrt(2 * kPi);
    const double mass = std::erf(a / std::sqrt(2.0));
    return std::sqrt(1 - 2 * a * phi / mass);
}

TEST(LensErrors, DrawnErrorsHaveTheRequestedStatistics)
{
    const ErrorSpec e = spec(0.002, 0.001, 0.02, 3, 42);
    const std::shared_ptr<const LensErrors> errors = LensErrors::drawn(e);
    std::vector<double> dx, dy, dz, focal, cos_tilt, cos_azimuth;
    const int n = 200;
    for (int l = -n / 2; l < n / 2; ++l)
        for (int k = -n / 2; k < n / 2; ++k) {
            const LensError x = errors->at(LensIndex{k, l});
            dx.push_back(x.dx_mm);
            dy.push_back(x.dy_mm);
            dz.push_back(x.dz_mm);
            focal.push_back(x.focal_factor - 1);
            cos_tilt.push_back(std::cos(x.tilt_deg * kPi / 180));
            cos_azimuth.push_back(std::cos(x.tilt_azimuth_deg * kPi / 180));
            ASSERT_LE(x.tilt_deg, 3.0);
            ASSERT_NEAR(length(x.axis), 1.0, 1e-12);
            ASSERT_NEAR(x.axis.z, std::cos(x.tilt_deg * kPi / 180), 1e-12);
        }
    const double count = double(dx.size());
    const double cut = truncated_sd(kErrorSigmas);
    struct Case {
        const char* name;
        const std::vector<double>* values;
        double sd;
    } cases[] = {{"dx", &dx, 0.002}, {"dy", &dy, 0.002}, {"dz", &dz, 0.001}, {"focal", &focal, 0.02}};
    for (const Case& c : cases) {
        const Moments m = moments(*c.values);
        // Mean within 4 standard errors; the sample sd within 4 of its standard errors (sd / sqrt(2n)).
        EXPECT_LT(std::fabs(m.mean), 4 * c.sd / std::sqrt(count)) << c.name;
        EXPECT_NEAR(m.sd, c.sd * cut, 4 * c.sd / std::sqrt(2 * count)) << c.name;
        EXPECT_LE(m.largest, kErrorSigmas * c.sd * (1 + 1e-12)) << c.name;
        EXPECT_GT(m.largest, 3 * c.sd) << c.name << ": 40000 normal draws reach 3 sd";
    }
    // Uniform over the cap: cos(tilt) uniform in [cos R, 1] (mean and variance of a uniform).
    const double lo = std::cos(3 * kPi / 180);
    const Moments ct = moments(cos_tilt);
    EXPECT_NEAR(ct.mean, 0.5 * (1 + lo), 4 * (1 - lo) / std::sqrt(12 * count));
    EXPECT_NEAR(ct.sd, (1 - lo) / std::sqrt(12.0), 0.02 * (1 - lo) / std::sqrt(12.0));
    EXPECT_LT(std::fabs(moments(cos_azimuth).mean), 4 / std::sqrt(2 * count));
    // Neighbours are independent: correlation of dx between lens k and k + 1.
    double c = 0, v = 0;
    for (std::size_t i = 0; i + 1 < dx.size(); ++i) {
        c += dx[i] * dx[i + 1];
        v += dx[i] * dx[i];
    }
    EXPECT_LT(std::fabs(c / v), 4 / std::sqrt(count));
}

TEST(LensErrors, SameSeedSameLensesInAnyOrderOnAnyThread)
{
    const ErrorSpec e = spec(0.001, 0.0005, 0.01, 1, 7);
    const std::shared_ptr<const LensErrors> a = LensErrors::drawn(e), b = LensErrors::drawn(e);
    std::vector<LensError> forwards, on_thread(100);
    for (int i = 0; i < 100; ++i)
        forwards.push_back(a->at(LensIndex{i * 37 - 1800, 5 - i}));
    std::thread worker([&]() {
        for (int i = 99; i >= 0; --i)
            on_thread[i] = b->at(LensIndex{i * 37 - 1800, 5 - i});
    });
    worker.join();
    for (int i = 0; i < 100; ++i) {
        EXPECT_EQ(forwards[i].dx_mm, on_thread[i].dx_mm);
        EXPECT_EQ(forwards[i].dz_mm, on_thread[i].dz_mm);
        EXPECT_EQ(forwards[i].focal_factor, on_thread[i].focal_factor);
        EXPECT_EQ(forwards[i].tilt_azimuth_deg, on_thread[i].tilt_azimuth_deg);
    }
    // Another seed, other lenses; a zero deviation leaves the others' draws as they were.
    const std::shared_ptr<const LensErrors> other = LensErrors::drawn(spec(0.001, 0.0005, 0.01, 1, 8));
    const std::shared_ptr<const LensErrors> flat = LensErrors::drawn(spec(0.001, 0, 0.01, 1, 7));
    int same = 0;
    for (int i = 0; i < 100; ++i) {
        const LensIndex lens{i * 37 - 1800, 5 - i};
        same += other->at(lens).dx_mm == forwards[i].dx_mm;
        EXPECT_EQ(flat->at(lens).dx_mm, forwards[i].dx_mm);
        EXPECT_EQ(flat->at(lens).focal_factor, forwards[i].focal_factor);
        EXPECT_EQ(flat->at(lens).dz_mm, 0.0);
        EXPECT_FALSE(std::signbit(flat->at(lens).dz_mm));
    }
    EXPECT_EQ(same, 0);
}

TEST(LensErrors, DisplacedLensesAreFoundFromTheirCellAndNeighbours)
{
    for (GridType grid : {GridType::Hexagonal, GridType::Rectangular}) {
        ArrayParams params = thin_array(grid, 0.1, 0.4);
        params.has_errors = true;
        params.errors = spec(0.1 / (4 * kErrorSigmas * std::sqrt(2.0)) * 0.99, 0, 0, 0, 3);  // the largest allowed
        const MicrolensArray array = make_microlens_array(params, -10);
        std::mt19937_64 random(5);
        std::uniform_real_distribution<double> coordinate(-2, 2);
        for (int n = 0; n < 20000; ++n) {
            const double x = coordinate(random), y = coordinate(random);
            // Brute force: the nearest actual centre over a 7 x 7 block of lattice indices.
            const LensIndex cell = nearest_lens(grid, 0.1, x, y);
            LensIndex best = cell;
            double best_sq = INFINITY;
            for (int dl = -3; dl <= 3; ++dl)
                for (int dk = -3; dk <= 3; ++dk) {
                    const LensIndex lens{cell.k + dk, cell.l + dl};
                    const Vec2 c = array.centre_local(lens);
                    const double sq = (x - c.x) * (x - c.x) + (y - c.y) * (y - c.y);
                    if (sq < best_sq) {
                        best_sq = sq;
                        best = lens;
                    }
                }
            ASSERT_EQ(array.nearest(x, y), best) << "at " << x << ", " << y;
        }
    }
}

TEST(LensErrors, ATiltedThinLensFocusesOnItsOwnAxis)
{
    // Light parallel to a lens's axis converges at its focal point, f along the axis from its
    // centre (the thin-lens definition), whatever the array's frame; and rays from that point leave
    // parallel to the axis.
    ArrayParams params = thin_array(GridType::Hexagonal, 0.1, 0.4);
    params.has_errors = true;
    params.errors = spec(0.002, 0.002, 0.05, 8, 9);
    const MicrolensArray array = make_microlens_array(params, -10);
    for (int k = -3; k <= 3; ++k) {
        const LensIndex lens{k, 2 - k};
        const LensError e = array.error_of(lens);
        ASSERT_GT(e.tilt_deg, 0);
        const double f = array.focal_length_mm(lens);
        EXPECT_NEAR(f, 0.4 * e.focal_factor, 1e-15);
        const Vec3 c = array.centre_mm(lens);
        const Vec3 focus = c - f * e.axis;  // behind the lens, towards the sensor
        const Vec3 u = normalized(cross(e.axis, Vec3{1, 0, 0})), v = cross(e.axis, u);
        for (double a : {-0.03, 0.0, 0.02})
            for (double b : {-0.02, 0.01, 0.035}) {
                // A point of the lens's own plane, reached by light travelling along -axis.
                const Vec3 h = c + a * u + b * v;
                const ArrayRay out = array.microlens->towards_sensor(array, lens, h + 5.0 * e.axis, -1.0 * e.axis);
                ASSERT_TRUE(out.passed);
                EXPECT_LT(length(cross(focus - out.origin, out.direction)) / length(out.direction), 1e-12)
                    << "lens " << k << ": the bent ray misses the focal point";
                EXPECT_LT(length(out.origin - h), 1e-12) << "the light meets the lens's own plane at h";
            }
        for (double u_s : {0.1, 0.5, 0.85}) {
            const ArrayRay ray = array.microlens->sample_ray(array, focus, lens, u_s, 1 - u_s);
            ASSERT_TRUE(ray.passed);
            EXPECT_LT(length(cross(normalized(ray.direction), e.axis)), 1e-12) << "rays from the focal point leave parallel";
        }
    }
}

TEST(LensErrors, FillFactorIsTheLensShareOfTheCellAndTheGapPassesLightUnbent)
{
    for (GridType grid : {GridType::Hexagonal, GridType::Rectangular}) {
        for (double fill : {0.3, 0.75, 0.9}) {
            ArrayParams params = thin_array(grid, 0.1, 0.4);
            params.fill_factor = fill;
            const MicrolensArray clear = make_microlens_array(params, -10);
            params.mask = true;
            const MicrolensArray masked = make_microlens_array(params, -10);
            const int n = 400;
            long long inside = 0, passed_masked = 0;
            const Vec3 p{0.013, -0.021, -10.4};
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const double u = (i + 0.5) / n, v = (j + 0.5) / n;
                    const bool lens_part = clear.in_aperture(clear.cell_point(u, v));
                    inside += lens_part;
                    const ArrayRay m = masked.microlens->sample_ray(masked, p, LensIndex{0, 0}, u, v);
                    passed_masked += m.passed;
                    EXPECT_EQ(m.passed, lens_part);
                    const ArrayRay c = clear.microlens->sample_ray(clear, p, LensIndex{0, 0}, u, v);
                    ASSERT_TRUE(c.passed);
                    if (!lens_part) {
                        // Unbent: the ray continues the line from p through the cell point.
                        EXPECT_LT(length(cross(normalized(c.direction), normalized(c.origin - p))), 1e-12);
                    }
                }
            // The cell map is uniform, so the share of grid points is the area share (to the grid's
            // resolution along the aperture's rim).
            EXPECT_NEAR(double(inside) / (double(n) * n), fill, 4.0 / n) << "fill factor " << fill;
            EXPECT_EQ(passed_masked, inside);
        }
    }
}

TEST(LensErrors, LensTableReadsItsColumnsByName)
{
    const std::string text =
        "# measured\n"
        "l,k,dx_mm,dy_mm,focal_length_mm,tilt_deg,tilt_azimuth_deg,comment\n"
        "0,0,0.001,-0.002,0.41,1.5,90,centre\n"
        "2,-1,,0.0005,,,,\n";
    const ParsedLensTable table = parse_lens_table(text, 0.1);
    ASSERT_EQ(table.error, "");
    ASSERT_EQ(table.rows.size(), 2u);
    EXPECT_EQ(table.rows[0].lens, (LensIndex{0, 0}));
    EXPECT_EQ(table.rows[0].error.dx_mm, 0.001);
    EXPECT_EQ(table.rows[0].error.dy_mm, -0.002);
    EXPECT_EQ(table.rows[0].focal_length_mm, 0.41);
    EXPECT_EQ(table.rows[1].lens, (LensIndex{-1, 2}));
    EXPECT_EQ(table.rows[1].error.dx_mm, 0.0);
    EXPECT_EQ(table.rows[1].focal_length_mm, 0.0);

    const double focal[1] = {0.4};
    const std::shared_ptr<const LensErrors> errors = LensErrors::tabled(table.rows, "t.csv", focal, 1);
    EXPECT_NEAR(errors->at(LensIndex{0, 0}).focal_factor, 0.41 / 0.4, 1e-15);
    EXPECT_NEAR(errors->at(LensIndex{0, 0}).axis.y, std::sin(1.5 * kPi / 180), 1e-15);
    EXPECT_EQ(errors->at(LensIndex{5, 5}).dx_mm, 0.0);  // not in the table: ideal
    EXPECT_EQ(errors->at(LensIndex{5, 5}).focal_factor, 1.0);

    struct Bad {
        const char* text;
        int line;
        const char* says;
    } bad[] = {
        {"dx_mm,dy_mm\n0.001,0\n", 1, "k and l"},
        {"k,l,dx_mm\n0,0,0.03\n", 2, "quarter of the pitch"},
        {"k,l,dx_mm\n0,0,abc\n", 2, "not a finite number"},
        {"k,l\n0,0\n1,0\n0,0\n", 4, "given twice (first on line 2)"},
        {"k,l,tilt_deg\n0,0,45\n", 2, "tilt_deg"},
        {"k,l\n0.5,0\n", 2, "whole numbers"},
        {"k,l,focal_length_mm\n0,0,-1\n", 2, "positive"},
        {"k,l,focal_length_mm\n0,0,\n1,0,0\n", 3, "positive (or empty: the lens type's), got 0"},
        {"# nothing\n", 1, "empty"},
    };
    for (const Bad& b : bad) {
        const ParsedLensTable t = parse_lens_table(b.text, 0.1);
        EXPECT_EQ(t.error_line, b.line) << b.text;
        EXPECT_NE(t.error.find(b.says), std::string::npos) << b.text << " -> " << t.error;
        EXPECT_TRUE(t.rows.empty());
    }
}

} // namespace
} // namespace plenoptic
