// SPDX-License-Identifier: AGPL-3.0-or-later
// Radiometry of the plenoptic camera: what a pixel's value measures.
//
// A pixel's samples are points s of the pixel and points q of a sampled aperture domain of
// area A (the exit pupil's disc without an array, a microlens cell with one), each weighted by
// whether its ray passes every aperture. Under `radiometry flat` a pixel is the radiance L times
// the share of A that passes: the first phase's camera, equal to the stock cameras. Under
// `radiometry irradiance` it is the sensor irradiance over a constant C,
//
//     E(s) / C = (L / C) * integral over the passing q of cos(t_s) cos(t_q) / |q - s|^2 dA,
//
// t_s the ray's angle to the sensor's normal, t_q its angle to the aperture plane's normal: on
// planes parallel at distance h this is the cos^4 law, cos^4(t) / h^2. A sample's colour is then
// weighted by K cos(t_s) cos(t_q) / |q - s|^2 with K = A / C (irradiance_weight); under flat by 1.
//
// C makes an on-axis pixel whose sampled aperture is wholly lit see radiance L as L. Without an
// array the domain is the exit pupil, a disc of radius a at distance h from the sensor, and
// C = pi a^2 / (h^2 + a^2) (a pinhole: the limit a -> 0, so a pixel is L cos^4). With an array it
// is a microlens's cell, seen from the point at distance d under the lens's centre:
// C = A_cell * mean(cos^4) / d^2 (pinhole microlenses: the limit of a shrinking cell). So a white
// world's microimages peak near 1 where their cell is wholly lit (the centre of a matched
// plenoptic 1.0 microimage) and fall off with the cos^4 law within a microimage and across the
// sensor. C is written to the metadata (sensor.radiometry), so E = value * C * L.
//
// A pixel's angular response (`sensor { angular_response e }`, on-chip microlenses) weighs each
// ray by cos^e of its angle to the sensor's normal as well; C then holds the same factor (mean of
// cos^(4+e) instead of cos^4 above), so the on-axis rule still holds.

#ifndef PLENOPTIC_RADIOMETRY_H
#define PLENOPTIC_RADIOMETRY_H

#include <cmath>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/core/irradiance.h"
#include "plenoptic/core/vec.h"

namespace plenoptic {

// K = A / C of the model's sampled aperture domain (mm^2), for make_camera; 0 under flat radiometry.
double irradiance_constant_mm2(const PlenopticCamera& model);

// C, the projected solid angle (sr) by which irradiance values are divided: E = value * C * L.
// 0 under flat radiometry and where C is a pinhole's limit (a pinhole main lens without an
// array, pinhole microlenses).
double reference_projected_solid_angle_sr(const PlenopticCamera& model);

// "flat" or "irradiance", as the scene writes it.
const char* radiometry_name(Radiometry radiometry);

} // namespace plenoptic

#endif
