// SPDX-License-Identifier: AGPL-3.0-or-later
// Sensor offset from the optical axis, non-square pixels (0.1 x 0.12 mm).
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 4 focus_distance 3 }
  microlens_array { hexagonal pitch 0.8 focal_length 3.2 distance 3.2 }
  sensor { pixel_size <0.1, 0.12> offset <0.55, -0.3> }
  samples 4
}
