// SPDX-License-Identifier: AGPL-3.0-or-later
// bare_array_rotate_up.pov: the 2018 report's bare microlens array, rotated 20 degrees about
// the camera's up axis: no main lens; 30 x 30 square lenses of pitch 0.8 mm and focal length 3
// mm cover the 24 mm sensor, 3 mm in front of it (the report's d = 1/8 unit; units in
// report2018.inc). The same as about the right axis, turned a quarter: one side of the array
// tilts away from the sensor (larger, blurred pictures), the other towards it and, beyond 3 /
// tan 20 = 8.2 mm from the centre, behind it (no light).
//
// Render from the repository root (any size: the sensor is always 24 mm wide):
//   build/povray +Iscenes/report2018/bare_array_rotate_up.pov +Lscenes/report2018 +Obare_array_rotate_up.png +W480 +H480

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
    rotate <0, 20, 0>                // 20 degrees about the camera's up axis
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 256                      // overlapping or tilted: many lenses per pixel
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
