// SPDX-License-Identifier: AGPL-3.0-or-later
// array_translate_z.pov: the 2018 report's full plenoptic camera, with the array translated by
// 0.4 unit along the axis. The report's camera in its normalised units (one unit = 24 mm,
// report2018.inc): a main lens of focal length F = 10 units (240 mm) with the array D = 15/8
// units (45 mm) behind it, 30 x 30 square microlenses of pitch 1/30 unit (0.8 mm) and focal
// length 1/8 unit (3 mm), and a sensor 1 unit (24 mm) wide. D < F: the main lens cannot focus
// any real object onto the array: the 6.2 m sphere's image lies 1 / (1/240 - 1/6200) = 250 mm
// behind the lens, far beyond the sensor, so on the array each scene point covers a disc of A
// (250 - 45) / 250 = 9.8 mm, about 12 lenses. The other reading of the report's translation:
// the array moves 0.4 unit (9.6 mm) towards the main lens, so D = 35.4 mm and d = 12.6 mm. The
// microlenses are no longer focused on the aperture (d > f): each lens's light spreads over A d
// / D + p |1 + d/D - d/f| = 4.3 + 2.3 mm, six cells, and the microimages overlap as with d =
// 5/8.
//
// Render from the repository root (any size: the sensor's width is fixed in mm):
//   build/povray +Iscenes/report2018/array_translate_z.pov +Lscenes/report2018 +Oarray_translate_z.png +W480 +H480

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
    focal_length R18_Microlens_F     // 3 mm
    distance R18_d                   // d = 3 mm before the translation
    translate <0, 0, 0.4 * R18_Unit> // 9.6 mm towards the main lens
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 256                      // overlapping or tilted: many lenses per pixel
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
