// SPDX-License-Identifier: AGPL-3.0-or-later
// full_d5_8.pov: the 2018 report's full plenoptic camera, with d = 5/8. The report's camera in
// its normalised units (one unit = 24 mm, report2018.inc): a main lens of focal length F = 10
// units (240 mm) with the array D = 15/8 units (45 mm) behind it, 30 x 30 square microlenses of
// pitch 1/30 unit (0.8 mm) and focal length 1/8 unit (3 mm), and a sensor 1 unit (24 mm) wide.
// D < F: the main lens cannot focus any real object onto the array: the 6.2 m sphere's image
// lies 1 / (1/240 - 1/6200) = 250 mm behind the lens, far beyond the sensor, so on the array
// each scene point covers a disc of A (250 - 45) / 250 = 9.8 mm, about 12 lenses. d = 5/8 unit
// (15 mm), five times the microlenses' focal length: each lens's light spreads over a patch A d
// / D + p |1 + d/D - d/f| = 4 + 2.9 mm wide on the sensor, six and a half microimage cells
// (1.07 mm), so neighbouring microimages overlap and every pixel sums light through about 40
// lenses (the patch, a 2.9 mm square widened by the 4 mm disc, covers 44.6 mm^2; a cell 1.14
// mm^2). The microimage centres also spread out: (D + d) / D = 1.33 times the pitch, so only
// 22.5 of them fit across the sensor.
//
// Render from the repository root (any size: the sensor's width is fixed in mm):
//   build/povray +Iscenes/report2018/full_d5_8.pov +Lscenes/report2018 +Ofull_d5_8.png +W480 +H480

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
    distance 5/8 * R18_Unit       // d = 15 mm
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 256                      // overlapping or tilted: many lenses per pixel
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
