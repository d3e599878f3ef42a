// SPDX-License-Identifier: AGPL-3.0-or-later
// Adaptive sampling (4 to 32 rays per pixel, stopping on confidence and variance) on a
// blurred focused-plenoptic view, where the count per pixel really varies. At f/2.8 the
// microimages overlap (their light adds), so the world is lit at half exposure.
#version 3.7;
#declare Golden_Exposure = 0.5;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 2.8 focus_distance 1.6 }
  microlens_array { hexagonal pitch 0.8 focal_length 3.2 distance 4.0 }
  sensor { pixel_size 0.1 }
  samples 4, 32 confidence 0.9 variance 1/200
}
