// SPDX-License-Identifier: AGPL-3.0-or-later
// Pinhole main lens, no array: a perspective camera with focal length D = 25 mm.
// Also writes the depth map (depth of a perspective view).
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { pinhole distance 25 }
  sensor { pixel_size 16 / 96 }   // 16 mm wide at 96 x 72, as the 160 x 120 scenes
  depth_map
}
