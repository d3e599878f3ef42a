// SPDX-License-Identifier: AGPL-3.0-or-later
// Thin main lens + hexagonal pinhole array: the chief-ray model. Rendered with POV-Ray's
// adaptive anti-aliasing (+A, see scenes.json) to cover the camera under supersampling.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 4 focus_distance 3 }
  microlens_array { hexagonal pitch 0.8 pinhole distance 3.2 }
  sensor { pixel_size 0.1 }
}
