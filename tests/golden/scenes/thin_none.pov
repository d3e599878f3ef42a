// SPDX-License-Identifier: AGPL-3.0-or-later
// Thin main lens, no array: a thin-lens camera focused on the sphere (2.2 m), f/2,
// 16 fixed samples per pixel: the box and the wall are blurred.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 2 focus_distance 2.2 }
  sensor { pixel_size 0.1 }
  samples 16
}
