// SPDX-License-Identifier: AGPL-3.0-or-later
// Multi-focus (Raytrix-like) hexagonal array: three interleaved lens types.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 5.6 focus_distance 1.6 }
  microlens_array { hexagonal pitch 0.8 focal_lengths <2.8, 3.2, 3.6> distance 4.0 }
  sensor { pixel_size 0.1 }
  samples 8
}
