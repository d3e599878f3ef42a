// SPDX-License-Identifier: AGPL-3.0-or-later
// A real microlens array: manufacturing errors (displaced, scaled and tilted lenses), a fill factor
// of 0.85 with a masked gap, behind a thin lens; plenoptic 1.0, 8 samples.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 4 focus_distance 3 }
  microlens_array {
    hexagonal pitch 0.8 focal_length 3.2 distance 3.2
    errors { position 0.02, 0.01 focal_length 0.02 rotation 2 seed 3 }
    fill_factor 0.85 mask on
  }
  sensor { pixel_size 0.1 }
  samples 8
}
