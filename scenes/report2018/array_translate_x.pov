// SPDX-License-Identifier: AGPL-3.0-or-later
// array_translate_x.pov: the 2018 report's full plenoptic camera, with the array translated by
// 0.4 unit sideways. The report's camera in its normalised units (one unit = 24 mm,
// report2018.inc): a main lens of focal length F = 10 units (240 mm) with the array D = 15/8
// units (45 mm) behind it, 30 x 30 square microlenses of pitch 1/30 unit (0.8 mm) and focal
// length 1/8 unit (3 mm), and a sensor 1 unit (24 mm) wide. D < F: the main lens cannot focus
// any real object onto the array: the 6.2 m sphere's image lies 1 / (1/240 - 1/6200) = 250 mm
// behind the lens, far beyond the sensor, so on the array each scene point covers a disc of A
// (250 - 45) / 250 = 9.8 mm, about 12 lenses. The array moves 0.4 unit (9.6 mm) along the
// camera's right axis. That is exactly 12 pitches, and the camera's array has no edge
// (docs/camera.md), so the raw is the raw of full_d1_8.pov: a periodic array shifted by whole
// pitches is the same array. The report's finite 30 x 30 array would leave a 0.4 unit wide
// strip of the sensor without lenses (docs/report2018.md).
//
// Render from the repository root (any size: the sensor's width is fixed in mm):
//   build/povray +Iscenes/report2018/array_translate_x.pov +Lscenes/report2018 +Oarray_translate_x.png +W480 +H480

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "report2018.inc"

#ifndef (R18_Translate_X)                // the translation, in units (tests/report2018 tries 0.4 + 1/60)
#declare R18_Translate_X = 0.4;
#end

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
    distance R18_d                   // d = 3 mm
    translate <R18_Translate_X * R18_Unit, 0, 0>   // 0.4 unit: 9.6 mm sideways = 12 pitches
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 64
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
