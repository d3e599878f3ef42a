// SPDX-License-Identifier: AGPL-3.0-or-later
// Irradiance radiometry against the optics written out here: the cos^4 law of
// a pinhole, the view factor of a parallel disc, the cos^4 integral over a microlens cell, and
// the etendue through an ideal microlens array. A uniform world of radiance 1
// (every ray returns 1), so a pixel's value is E / C.

#include <cmath>

#include <gtest/gtest.h>

#include "plenoptic/camera/pixel.h"
#include "plenoptic/camera/radiometry.h"
#include "plenoptic/core/test_util.h"

namespace plenoptic {
namespace {



Rgbt white(const OpticsRay&) { return Rgbt{1, 1, 1, 1}; }

// Sensor point (x, y) of pixel (i, j)'s centre, as sensor_point places it (pixel (W/2, H/2) on
// the axis for odd W, H), written out so the tests do not take positions from the code.
double centre_x(int i, int W, double pixel) { return -(i + 0.5 - 0.5 * W) * pixel; }
double centre_y(int j, int H, double pixel) { return (j + 0.5 - 0.5 * H) * pixel; }

// A pinhole 50 mm in front of a sensor of 0.5 mm pixels, no array, irradiance radiometry.
CameraParams irradiance_pinhole()
{
    CameraParams p;
    p.main.given = true;
    p.main.type = MainLensType::Pinhole;
    p.main.has_distance = true;
    p.main.distance_mm = 50;
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.5;
    p.radiometry = Radiometry::Irradiance;
    return p;
}

TEST(Radiometry, PinholeWithoutArrayFallsOffAsCos4AndIsOneOnAxis)
{
    CameraParams p = irradiance_pinhole();
    ASSERT_EQ(check_camera(p), "");
    const PlenopticCamera m = make_camera(p);
    const int W = 201, H = 151;
    double worst = 0;
    for (int j = 0; j < H; j += 15)
        for (int i = 0; i < W; i += 20) {
            const double x = centre_x(i, W, 0.5), y = centre_y(j, H, 0.5);
            const double cos2 = 2500 / (2500 + x * x + y * y);
            worst = std::max(worst, std::fabs(shade_pixel(with_film(m, W, H), i, j, white).r - cos2 * cos2));
        }
    EXPECT_LT(worst, 1e-12);
    EXPECT_NEAR(shade_pixel(with_film(m, W, H), 100, 75, white).r, 1, 1e-15);
    // Flat radiometry is the stock perspective camera: 1 everywhere.
    p.radiometry = Radiometry::Flat;
    EXPECT_EQ(shade_pixel(with_film(make_camera(p), W, H), 0, 0, white).r, 1);
}

// E / L of a point at distance r from the axis of a Lambertian disc of radius a, parallel to the
// point's plane at distance h: the configuration factor of a parallel disc.
double disc_irradiance(double a, double h, double r)
{
    const double s = h * h + r * r + a * a;
    return kPi / 2 * (1 - (h * h + r * r - a * a) / std::sqrt(s * s - 4 * r * r * a * a));
}

TEST(Radiometry, ThinLensWithoutArrayMatchesTheDiscViewFactorAcrossTheSensor)
{
    // 50 mm f/2 (pupil radius 12.5 mm) at D = 52 mm: the pupil subtends a wide cone.
    CameraParams p = test::thin_lens_camera(50, 2, 52);
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.25;
    p.sampling.samples = 4096;
    p.radiometry = Radiometry::Irradiance;
    const PlenopticCamera m = make_camera(p);
    const int W = 241, H = 3;
    const double a = 12.5, h = 52;
    const double on_axis = disc_irradiance(a, h, 0);
    EXPECT_NEAR(on_axis, kPi * a * a / (h * h + a * a), 1e-12);
    double worst = 0;
    for (int i = 120; i < W; i += 10) {
        const double r = std::fabs(centre_x(i, W, 0.25));
        const double expected = disc_irradiance(a, h, r) / on_axis;
        const double got = shade_pixel(with_film(m, W, H), i, 1, white).r;
        worst = std::max(worst, std::fabs(got / expected - 1));
    }
    // 4096 stratified samples of a smooth integrand; the pixel (0.25 mm) is as good as a point.
    EXPECT_LT(worst, 2e-3) << worst;
    // 30 mm off axis the falloff is large: the test would see a missing cos^4.
    EXPECT_LT(disc_irradiance(a, h, 30) / on_axis, 0.6);
}

// (1/d^2) * integral over a square cell of side `pitch` centred at (cx, cy) of cos^4 seen from
// (x, y) at distance d: a 400 x 400 midpoint sum.
double cell_cos4(double pitch, double cx, double cy, double d, double x, double y)
{
    const int n = 400;
    const double step = pitch / n;
    double total = 0;
    for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a) {
            const double qx = cx - pitch / 2 + (a + 0.5) * step - x;
            const double qy = cy - pitch / 2 + (b + 0.5) * step - y;
            const double cos2 = d * d / (d * d + qx * qx + qy * qy);
            total += cos2 * cos2 / (d * d) * step * step;
        }
    return total;
}

TEST(Radiometry, BareArrayMicroimageFollowsTheCos4IntegralOverItsCell)
{
    // Square f/2 microlenses (pitch 0.1 mm, f = d = 0.2 mm) and no main lens: every ray passes,
    // so a pixel is the cos^4 integral over its lens's cell, and 1 under a lens's centre.
    CameraParams p;
    test::add_array(&p, GridType::Rectangular, 0.1, 0.2, 0.2);
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.004;
    p.sampling.samples = 1024;
    p.radiometry = Radiometry::Irradiance;
    ASSERT_EQ(check_camera(p), "");
    const PlenopticCamera m = make_camera(p);
    const int W = 75, H = 75;  // 3 x 3 lenses of 25 pixels; pixel (37, 37) under the centre lens's centre
    const double reference = cell_cos4(0.1, 0, 0, 0.2, 0, 0);
    double worst = 0;
    for (int j = 25; j < 50; j += 3)
        for (int i = 25; i < 50; i += 3) {
            const double x = centre_x(i, W, 0.004), y = centre_y(j, H, 0.004);
            const double expected = cell_cos4(0.1, 0, 0, 0.2, x, y) / reference;
            worst = std::max(worst, std::fabs(shade_pixel(with_film(m, W, H), i, j, white).r / expected - 1));
        }
    EXPECT_LT(worst, 2e-3) << worst;
    // The falloff within the microimage is large enough to see: a corner pixel of the cell.
    EXPECT_LT(cell_cos4(0.1, 0, 0, 0.2, 0.048, 0.048) / reference, 0.92);
    EXPECT_NEAR(shade_pixel(with_film(m, W, H), 37, 37, white).r, 1, 2e-3);
}

// The mean of cos^4 over a hexagonal cell of pitch p seen from distance d under its centre, on
// its cell: a 400 x 400 midpoint sum over the cell's bounding box.
double hexagon_mean_cos4(double pitch, double d)
{
    const int n = 400;
    double total = 0;
    long inside = 0;
    for (int b = 0; b < n; ++b)
        for (int a = 0; a < n; ++a) {
            // The cell's bounding box: inradius p/2 across, circumradius p/sqrt(3) up and down.
            const double x = -pitch / 2 + (a + 0.5) * pitch / n;
            const double y = (-1 + (b + 0.5) * 2 / n) * pitch / std::sqrt(3.0);
            if (test::brute_force_nearest(GridType::Hexagonal, pitch, x, y) != LensIndex{0, 0})
                continue;
            const double cos2 = d * d / (d * d + x * x + y * y);
            total += cos2 * cos2;
            ++inside;
        }
    return total / inside;
}

TEST(Radiometry, AnIdealArrayPassesTheEtendueOfItsCellThroughTheMainPupil)
{
    // Plenoptic 1.0, f-number matched (f/4 main lens at D = 16.1 mm, hexagonal f/4 microlenses).
    // Integrated over the sensor, the centre lens's own light is (1/C) times the etendue from
    // its cell to the main lens's pupil, counted on the sensor's side of the microlens:
    //     G = integral over cell points q and pupil points m of cos^4(t) / D^2,
    // where t is the angle of the sensor-side slope w = (m - q) / D + q / f (the ideal thin lens
    // adds q / f to a slope). Without the bend (f infinite) G is the light the cell would receive
    // in the array's plane, A_cell * pi a^2 / (D^2 + a^2); the slope map conserves etendue only
    // paraxially, so the bend costs about 1.6 % here. C = A_cell * mean(cos^4 over the cell) / d^2.
    CameraParams p = test::plenoptic_camera(GridType::Hexagonal, 0.16, 0.64, 0.64, 16, 4, 16.1);
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.01;
    p.radiometry = Radiometry::Irradiance;
    const PlenopticCamera m = make_camera(p);
    const int W = 61, H = 61;  // 0.61 mm: the microimage (0.16 mm) and its rim with room to spare
    const LensIndex centre{0, 0};
    const int count = 256;
    double rendered = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            double sum = 0;
            for (int n = 0; n < count; ++n) {
                OpticsRay ray;
                if ((ray = generate_ray(with_film(m, W, H), i, j, make_sample(i, j, n, count), &centre)).passed)
                    sum += ray.weight;
            }
            rendered += sum / count * 0.01 * 0.01;
        }

    const double D = 16.1, a = 2, f = 0.64, d = 0.64, pitch = 0.16;
    const int nq = 48, nm = 64;
    double etendue = 0, bendless = 0;
    for (int qj = 0; qj < nq; ++qj)
        for (int qi = 0; qi < nq; ++qi) {
            const double half_height = pitch / std::sqrt(3.0);  // the cell's circumradius
            const double qx = -pitch / 2 + (qi + 0.5) * pitch / nq, qy = -half_height + (qj + 0.5) * 2 * half_height / nq;
            if (test::brute_force_nearest(GridType::Hexagonal, pitch, qx, qy) != centre)
                continue;  // outside the centre lens's hexagonal cell
            const double dq = (pitch / nq) * (2 * half_height / nq);
            for (int mj = 0; mj < nm; ++mj)
                for (int mi = 0; mi < nm; ++mi) {
                    const double mx = -a + (mi + 0.5) * 2 * a / nm, my = -a + (mj + 0.5) * 2 * a / nm;
                    if (mx * mx + my * my > a * a)
                        continue;
                    const double dm = (2 * a / nm) * (2 * a / nm);
                    const double wx = (mx - qx) / D + qx / f, wy = (my - qy) / D + qy / f;
                    const double w2 = wx * wx + wy * wy;
                    etendue += dq * dm / (D * D) / ((1 + w2) * (1 + w2));
                    const double vx = (mx - qx) / D, vy = (my - qy) / D;
                    const double v2 = vx * vx + vy * vy;
                    bendless += dq * dm / (D * D) / ((1 + v2) * (1 + v2));
                }
        }
    // The grids' masks miss a little of the hexagon's and the disc's areas (2 %); the ratio of the
    // two sums cancels that, and the bendless light is A_cell * pi a^2 / (D^2 + a^2) to 3e-5
    // (E falls by (q / D)^2 at most across the cell).
    const double cell_area = pitch * pitch * std::sqrt(3.0) / 2;
    const double in_array_plane = cell_area * kPi * a * a / (D * D + a * a);
    EXPECT_NEAR(bendless / in_array_plane, 1, 0.03);
    const double G = etendue / bendless * in_array_plane;
    EXPECT_LT(etendue / bendless, 0.99);  // the bend's loss is larger than the tolerance below
    const double C = cell_area * hexagon_mean_cos4(pitch, d) / (d * d);
    EXPECT_NEAR(rendered / (G / C), 1, 2e-3) << rendered << " " << G / C;
    EXPECT_NEAR(C, reference_projected_solid_angle_sr(m), 1e-4 * C);  // what the metadata reports
}

TEST(Radiometry, MicroimageCentresFallOffAcrossTheSensorAsTheirCellIsSeen)
{
    // Plenoptic 1.0 with a wide field: square f/4 microlenses (pitch 0.2 mm, f = d = 0.8 mm) at
    // D = 20.2 mm behind a 20 mm f/4 thin lens (pupil radius 2.5 mm). The pixel at the centre of
    // lens k's microimage, s = c_k (1 + d / D), receives through the whole cell rays that leave
    // parallel (slope -c_k / D) and all pass the pupil; so its value is the cos^4 integral over
    // the cell seen from s, over C: the cos^4 law of the chief ray's angle atan(c_k / D), which
    // reaches 31 degrees (cos^4 = 0.54) at the last lens.
    CameraParams p = test::plenoptic_camera(GridType::Rectangular, 0.2, 0.8, 0.8, 20, 4, 20.2);
    p.sensor.pixel_size_mm[0] = p.sensor.pixel_size_mm[1] = 0.002;
    p.sampling.samples = 1024;
    p.radiometry = Radiometry::Irradiance;
    ASSERT_EQ(check_camera(p), "");
    const PlenopticCamera m = make_camera(p);
    const int W = 12801, H = 3;
    const double D = 20.2, d = 0.8;
    const double reference = cell_cos4(0.2, 0, 0, d, 0, 0);  // C
    double worst = 0;
    for (int k : {0, 10, 20, 40, 60}) {
        const double c = -0.2 * k;  // lens k on the -x side: pixel indices grow towards -x
        const double s = c * (1 + d / D);
        const int i = int(std::lround(0.5 * W - 0.5 - s / 0.002));
        const double x = centre_x(i, W, 0.002);
        const double expected = cell_cos4(0.2, c, 0, d, x, centre_y(1, H, 0.002)) / reference;
        const double got = shade_pixel(with_film(m, W, H), i, 1, white).r;
        worst = std::max(worst, std::fabs(got / expected - 1));
        if (k == 0) {
            EXPECT_NEAR(got, 1, 2e-3);  // the on-axis pixel lit through its whole cell sees L as L
        }
        if (k == 60) {
            const double cos2 = D * D / (D * D + c * c);
            EXPECT_NEAR(got, cos2 * cos2, 0.01);
        }
    }
    EXPECT_LT(worst, 2e-3) << worst;
}

// (1/h^2) integral over a disc of radius a of cos^m, seen from a point at distance r from the
// disc's axis, h below it: a 600 x 600 polar midpoint sum.
double disc_cos_power(double a, double h, double r, double m)
{
    const int nr = 600, nt = 600;
    double total = 0;
    for (int i = 0; i < nr; ++i) {
        const double rho = (i + 0.5) / nr * a;
        for (int j = 0; j < nt; ++j) {
            const double t = (j + 0.5) / nt * 2 * kPi;
            const double dx = rho * std::cos(t) - r, dy = rho * std::sin(t);
            total += std::pow(h * h / (h * h + dx * dx + dy * dy), 0.5 * m) * rho * (a / nr) * (2 * kPi / nt);
        }
    }
    return total / (h * h);
}

TEST(Radiometry, AngularResponseMultipliesTheCos4LawAndKeepsTheAxisAtOne)
{
    // A pinhole: cos^(4 + e) exactly.
    CameraParams p = irradiance_pinhole();
    p.sensor.angular_exponent = 6;
    ASSERT_EQ(check_camera(p), "");
    const PlenopticCamera pinhole = with_film(make_camera(p), 201, 1);
    const double x = centre_x(170, 201, 0.5);
    const double cos2 = 2500 / (2500 + x * x);
    EXPECT_NEAR(shade_pixel(pinhole, 170, 0, white).r, std::pow(cos2, 5), 1e-12);

    // A 50 mm f/2 thin lens: the pixel is the integral of cos^(4 + e) over the pupil, 1 on the axis.
    CameraParams t = test::thin_lens_camera(50, 2, 52);
    t.sensor.pixel_size_mm[0] = t.sensor.pixel_size_mm[1] = 0.25;
    t.sampling.samples = 4096;
    t.radiometry = Radiometry::Irradiance;
    t.sensor.angular_exponent = 8;
    const PlenopticCamera thin = make_camera(t);
    const int W = 241;
    const double on_axis = disc_cos_power(12.5, 52, 0, 12);
    double worst = 0;
    for (int i = 120; i < W; i += 20) {
        const double r = std::fabs(centre_x(i, W, 0.25));
        const double expected = disc_cos_power(12.5, 52, r, 12) / on_axis;
        worst = std::max(worst, std::fabs(shade_pixel(with_film(thin, W, 3), i, 1, white).r / expected - 1));
    }
    EXPECT_LT(worst, 2e-3) << worst;
    // Without the response the same pixel 30 mm off axis is brighter: the test sees the exponent.
    EXPECT_LT(disc_cos_power(12.5, 52, 30, 12) / on_axis, 0.9 * disc_cos_power(12.5, 52, 30, 4) / disc_cos_power(12.5, 52, 0, 4));

    // Flat radiometry has no angular response: refused.
    t.radiometry = Radiometry::Flat;
    EXPECT_NE(check_camera(t).find("angular_response"), std::string::npos);
    t.sensor.angular_exponent = 65;
    EXPECT_NE(check_sensor(t.sensor).find("from 0 to 64"), std::string::npos);
}

TEST(Radiometry, RefusesIrradianceBehindAPinholeMainLensWithLensletMicrolenses)
{
    CameraParams p = test::plenoptic_camera(GridType::Hexagonal, 0.16, 0.64, 0.64, 16, 4, 16.1);
    p.main.type = MainLensType::Pinhole;
    p.main.has_focal_length = p.main.has_f_number = false;
    ASSERT_EQ(check_camera(p), "");
    p.radiometry = Radiometry::Irradiance;
    EXPECT_NE(check_camera(p).find("radiometry irradiance needs a main lens with an area"), std::string::npos)
        << check_camera(p);
}

} // namespace
} // namespace plenoptic
