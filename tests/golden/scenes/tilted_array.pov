// SPDX-License-Identifier: AGPL-3.0-or-later
// Array tilted about x and y (the metadata lattice is then an affine fit), shifted along z.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 4 focus_distance 3 }
  microlens_array { rectangular pitch 0.8 focal_length 3.2 distance 3.2 rotate <4, -3, 2> translate <0, 0.1, 0.05> }
  sensor { pixel_size 0.1 }
  samples 4
}
