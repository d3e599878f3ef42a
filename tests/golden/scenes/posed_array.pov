// SPDX-License-Identifier: AGPL-3.0-or-later
// Rotated (in plane, 7 degrees) and shifted array: the pose error of a real camera.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 4 focus_distance 3 }
  microlens_array { hexagonal pitch 0.8 focal_length 3.2 distance 3.2 rotate <0, 0, 7> translate <0.25, -0.1, 0> }
  sensor { pixel_size 0.1 }
  samples 4
}
