// SPDX-License-Identifier: AGPL-3.0-or-later
// Spectral sampling: a traced singlet of dispersing glass (V_d 25) and dispersing microlenses
// (V_d 40), plenoptic 1.0, 4 wavelength bands with the default sensor response, 8 samples.
#version 3.7;
#include "world.inc"
camera {
  plenoptic
  location Golden_Camera_Location
  look_at Golden_Look_At
  main_lens {
    prescription {
      stop { thickness 2 aperture 8 }
      surface { radius 45 thickness 5 ior 1.5168 aperture 20 abbe 25 }
      surface { radius -45 thickness 0 ior 1 aperture 20 }
    }
    focus_distance 3
  }
  microlens_array { hexagonal pitch 0.8 focal_length 3.2 distance 3.2 abbe 40 }
  sensor { pixel_size 0.1 }
  samples 8
  spectral 4
}
