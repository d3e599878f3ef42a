// SPDX-License-Identifier: AGPL-3.0-or-later
// Pinhole main lens in front of a thin-lens array. Each microlens images the main-lens
// pinhole 2.17 mm behind it (1/2.0 - 1/25.x); the sensor at 3.2 mm receives a disc of about
// 0.38 mm (4 pixels) per lens, a tiny view of the scene. (With d = f the discs would be
// single pixels.)
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { pinhole distance 25 }
  microlens_array { hexagonal pitch 0.8 focal_length 2.0 distance 3.2 }
  sensor { pixel_size 0.1 }
  samples 4
}
