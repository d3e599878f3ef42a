// SPDX-License-Identifier: AGPL-3.0-or-later
// bare_array_rotate_direction.pov: the 2018 report's bare microlens array, rotated 20 degrees
// about the viewing direction: no main lens; 30 x 30 square
// lenses of pitch 0.8 mm and focal length 3 mm cover the 24 mm sensor, 3 mm in front of it
// (the report's d = 1/8 unit; units in report2018.inc).
// The lattice turns in its own plane: the tiles (the lenses' cells) are turned by 20 degrees,
// but the picture inside each tile is not, because a round lens looks the same turned: every
// tile still shows the same upright patch of the scene.
//
// Render from the repository root (any size: the sensor is always 24 mm wide):
//   build/povray +Iscenes/report2018/bare_array_rotate_direction.pov +Lscenes/report2018 +Obare_array_rotate_direction.png +W480 +H480

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
    rotate <0, 0, 20>                // 20 degrees about the viewing direction
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 64
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
