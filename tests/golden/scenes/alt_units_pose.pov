// SPDX-License-Identifier: AGPL-3.0-or-later
// The other ways to say the same things: aperture (mm) instead of f_number, distance D
// instead of focus_distance, mm_per_unit 500 (the world looks twice as large), and a camera
// placed with sky, look_at and a rotate.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  mm_per_unit 500
  location <0.3, 1.0, -2.0>
  sky <0.05, 1, 0>
  look_at <0, 0.4, 1>
  rotate y * 4
  main_lens { thin_lens focal_length 25 aperture 8 distance 25.4 }
  microlens_array { rectangular pitch 0.8 focal_length 2.5 distance 2.5 }
  sensor { pixel_size 0.1 }
  samples 4
}
