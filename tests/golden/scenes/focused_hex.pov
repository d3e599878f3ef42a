// SPDX-License-Identifier: AGPL-3.0-or-later
// Focused plenoptic (2.0): the main lens focuses at 1.6 m, in front of the nearest object,
// so its image of the scene lies in front of the array; microlenses with d > f relay it.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 5.6 focus_distance 1.6 }
  microlens_array { hexagonal pitch 0.8 focal_length 3.2 distance 4.0 }
  sensor { pixel_size 0.1 }
  samples 8
}
