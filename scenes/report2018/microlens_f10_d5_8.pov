// SPDX-License-Identifier: AGPL-3.0-or-later
// microlens_f10_d5_8.pov: the 2018 report's full plenoptic camera, with focal length 10 and d =
// 5/8. The report's camera in its normalised units (one unit = 24 mm, report2018.inc): a main
// lens of focal length F = 10 units (240 mm) with the array D = 15/8 units (45 mm) behind it,
// 30 x 30 square microlenses of pitch 1/30 unit (0.8 mm) and focal length 1/8 unit (3 mm), and
// a sensor 1 unit (24 mm) wide. D < F: the main lens cannot focus any real object onto the
// array: the 6.2 m sphere's image lies 1 / (1/240 - 1/6200) = 250 mm behind the lens, far
// beyond the sensor, so on the array each scene point covers a disc of A (250 - 45) / 250 = 9.8
// mm, about 12 lenses. The report's f = 10 is already the main lens's (every scene here has
// it), so we read this set-up as microlenses of focal length 10 units (240 mm) at d = 5/8 unit
// (15 mm). Such lenses barely bend the light (p / f = 1/300), so the array is almost a window:
// the sensor receives the main lens's own image, 60 mm behind a 240 mm lens, blurred by A |(D +
// d) / F - 1| = 9 mm; the cells' edges shift light by at most p/2 x d / f = 0.025 mm and do not
// show. Like the thin lens with f > d, it is blurred; it does not vanish.
//
// Render from the repository root (any size: the sensor's width is fixed in mm):
//   build/povray +Iscenes/report2018/microlens_f10_d5_8.pov +Lscenes/report2018 +Omicrolens_f10_d5_8.png +W480 +H480

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "report2018.inc"

camera {
  plenoptic
  location R18_Location
  look_at  R18_Look_At
  main_lens {
    thin_lens
    focal_length R18_F               // 240 mm
    aperture R18_Aperture            // 12 mm: f-number matched at d = 3 mm
    distance R18_D                   // 45 mm to the array
  }
  microlens_array {
    rectangular
    pitch R18_Pitch                  // 0.8 mm
    focal_length 10 * R18_Unit       // 240 mm: almost no power
    distance 5/8 * R18_Unit       // d = 15 mm
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 256                      // overlapping or tilted: many lenses per pixel
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
