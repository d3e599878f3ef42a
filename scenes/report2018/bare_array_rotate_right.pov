// SPDX-License-Identifier: AGPL-3.0-or-later
// bare_array_rotate_right.pov: the 2018 report's bare microlens array, rotated 20 degrees about
// the camera's right axis: no main lens; 30 x 30 square lenses of pitch 0.8 mm and focal length
// 3 mm cover the 24 mm sensor, 3 mm in front of it (the report's d = 1/8 unit; units in
// report2018.inc). The array's upper half tilts away from the sensor (3 + 12 tan 20 = 7.4 mm
// above the sensor's edge) and its lower half towards it: below y = -3 / tan 20 = -8.2 mm it
// would lie behind the sensor, which no real array can, and those pixels receive nothing. Each
// lens's picture is scaled by its own distance to the sensor and blurred by p |d - f| / f where
// that distance d is not the focal length f. With the sensor read out upside down
// (docs/camera.md), the array's upper lenses fill the lower rows of the image. The irradiance
// goes as 1 / distance^2: the tiles dim where the array recedes and brighten (a PNG clips them)
// near the crossing.
//
// Render from the repository root (any size: the sensor is always 24 mm wide):
//   build/povray +Iscenes/report2018/bare_array_rotate_right.pov +Lscenes/report2018 +Obare_array_rotate_right.png +W480 +H480

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "report2018.inc"

camera {
  plenoptic
  location R18_Location              // the centre of the array
  look_at  R18_Look_At
  microlens_array {
    rectangular
    pitch R18_Pitch                  // 0.8 mm
    focal_length R18_Microlens_F     // 3 mm
    distance R18_d                   // 3 mm: each lens focuses the far scene on the sensor
    rotate <20, 0, 0>                // 20 degrees about the camera's right axis
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 256                      // overlapping or tilted: many lenses per pixel
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
