// SPDX-License-Identifier: AGPL-3.0-or-later
// No main lens, hexagonal array of thin lenses focused at infinity (d = f): 4 samples.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  microlens_array { hexagonal pitch 1.6 focal_length 2.0 distance 2.0 }
  sensor { pixel_size 0.1 }
  samples 4
}
