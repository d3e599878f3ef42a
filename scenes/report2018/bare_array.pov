// SPDX-License-Identifier: AGPL-3.0-or-later
// bare_array.pov: the 2018 report's bare microlens array, not rotated: no main lens; 30 x 30
// square
// lenses of pitch 0.8 mm and focal length 3 mm cover the 24 mm sensor, 3 mm in front of it
// (the report's d = 1/8 unit; units in report2018.inc).
// Each pixel sees through the lens straight above it (the camera's bare array is baffled,
// docs/camera.md), so each 0.8 mm tile is a sharp little picture of the same 15 degree patch of
// the scene straight ahead (2 atan(0.4 / 3)), the view of a lens 3 mm from its sensor. The
// tiles are upright and all alike: 0.8 mm apart, the lenses see a scene 4 m away with no
// visible parallax.
//
// Render from the repository root (any size: the sensor is always 24 mm wide):
//   build/povray +Iscenes/report2018/bare_array.pov +Lscenes/report2018 +Obare_array.png +W480 +H480

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
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 64
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
