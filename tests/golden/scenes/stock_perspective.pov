// SPDX-License-Identifier: AGPL-3.0-or-later
// Control: the same world through POV-Ray's own perspective camera with focal blur.
// The plenoptic changes must leave it untouched, and it must write no plenoptic metadata.
#version 3.7;
#include "world.inc"
camera {
  perspective
  location Golden_Camera_Location
  look_at Golden_Look_At
  angle 35
  aperture 0.2
  focal_point <-0.45, 0.35, -0.3>
  blur_samples 8
}
