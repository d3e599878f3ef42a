// SPDX-License-Identifier: AGPL-3.0-or-later
// Plenoptic 1.0 with the depth map: image, metadata and depth EXR are all compared.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 4 focus_distance 3 }
  microlens_array { hexagonal pitch 1.2 focal_length 4.8 distance 4.8 }
  sensor { pixel_size 0.15 }
  samples 4
  depth_map
}
