// SPDX-License-Identifier: AGPL-3.0-or-later
// Plenoptic 1.0 (d = f), rectangular grid, f-number matched, 8 samples.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 4 focus_distance 3 }
  microlens_array { rectangular pitch 0.8 focal_length 3.2 distance 3.2 }
  sensor { pixel_size 0.1 }
  samples 8
}
