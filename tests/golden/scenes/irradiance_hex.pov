// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic1_hex under irradiance radiometry: cos^4 falloff within each microimage and across the
// 16 x 12 mm sensor (21 degrees at the corners behind the 25 mm lens).
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 4 focus_distance 3 }
  microlens_array { hexagonal pitch 0.8 focal_length 3.2 distance 3.2 }
  sensor { pixel_size 0.1 }
  samples 8
  radiometry irradiance
}
