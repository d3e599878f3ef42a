// SPDX-License-Identifier: AGPL-3.0-or-later
// thin_lens_f5.pov: the 2018 report's thin-lens camera with f = 5 mm: no microlens array, the
// sensor 50 mm behind an ideal thin lens. One of the report's "classical" lenses: it focuses a
// plane 5.56 mm in front of it onto the sensor, so the far scene is blurred by b = 45 / 8 = 5.6
// mm.
//
// The optics: every sensor point sees the scene along the ray through the lens centre (the
// picture of a pinhole 50 mm in front of the sensor), blurred by the disc in which the lens
// spreads a scene point over the sensor. For a point at distance z that disc has diameter
//   b = A |D (1/F - 1/z) - 1|,  A = F / 8 (f/8),  D = 50 mm,
// so b = |D - F| / 8 for the far scene, whether F is shorter or longer than D.
// docs/report2018.md compares it with the report; tests/report2018 checks the blur against
// POV-Ray's own pinhole picture convolved with that disc.
//
// Render from the repository root (any size: the sensor is always 24 mm wide):
//   build/povray +Iscenes/report2018/thin_lens_f5.pov +Lscenes/report2018 +Othin_lens_f5.png +W480 +H480

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "report2018.inc"

camera {
  plenoptic
  location R18_Location
  look_at  R18_Look_At
  main_lens {
    thin_lens
    focal_length 5                  // mm
    f_number 8                       // A = F / 8
    distance 50                      // lens -> sensor, mm (there is no array)
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 256
}
