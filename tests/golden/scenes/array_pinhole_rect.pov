// SPDX-License-Identifier: AGPL-3.0-or-later
// No main lens, rectangular array of pinholes: a camera array; every 16 x 16 px microimage
// is a pinhole camera at its lens centre.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  microlens_array { rectangular pitch 1.6 pinhole distance 2.0 }
  sensor { pixel_size 0.1 }
}
