// SPDX-License-Identifier: AGPL-3.0-or-later
// Refracting microlenses: focused_hex's camera with plano-convex caps (R 1.6 mm, n 1.5: paraxial
// f = 3.2 mm) on a 0.3 mm substrate, facing the sensor, traced exactly through the glass.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens { thin_lens focal_length 25 f_number 5.6 focus_distance 1.6 }
  microlens_array {
    hexagonal pitch 0.8
    lens { surface { radius 1.6 } thickness 0.1 ior 1.5 substrate 0.3 curved_side sensor }
    distance 4.0
  }
  sensor { pixel_size 0.1 }
  samples 8
}
