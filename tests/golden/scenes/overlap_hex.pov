// SPDX-License-Identifier: AGPL-3.0-or-later
// Overlapping microimages: main lens at f/2 while the microlenses are f/4, so each
// microimage disc is twice as wide as the pitch and a pixel receives the light of up to about
// four lenses, which add: the world is lit at a quarter of its usual exposure.
#version 3.7;
#declare Golden_Exposure = 0.25;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 2 focus_distance 3 }
  microlens_array { hexagonal pitch 0.8 focal_length 3.2 distance 3.2 }
  sensor { pixel_size 0.1 }
  samples 16
}
