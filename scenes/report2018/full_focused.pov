// SPDX-License-Identifier: AGPL-3.0-or-later
// full_focused.pov: not in the report: its full camera at d = 1/8 (full_d1_8.pov) with the one
// change the optics asks for. With F = 10 units (240 mm) and D = 15/8 (45 mm) the main lens
// cannot focus any real object onto the array (D < F). A plenoptic 1.0 camera wants the scene
// focused on the array: here F = 1 / (1/45 + 1/6200) = 44.68 mm focuses the white sphere, 6.2 m
// away, onto it. On the array, a point anywhere in the scene (3.4 m to infinity) is then
// blurred by at most A |D (1/F - 1/z) - 1| = 0.09 mm, a ninth of a pitch, so every microimage
// is a flat disc of one colour: the raw a light-field decoder expects. Units in report2018.inc.
//
// Render from the repository root (any size: the sensor is always 24 mm wide):
//   build/povray +Iscenes/report2018/full_focused.pov +Lscenes/report2018 +Ofull_focused.png +W480 +H480

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "report2018.inc"

camera {
  plenoptic
  location R18_Location
  look_at  R18_Look_At
  main_lens {
    thin_lens
    focal_length 1 / (1 / R18_D + 1 / 6200)   // 44.68 mm: the sphere (6.2 m) in focus on the array
    aperture R18_Aperture            // 12 mm: f-number matched at d = 3 mm
    distance R18_D                   // 45 mm to the array
  }
  microlens_array {
    rectangular
    pitch R18_Pitch                  // 0.8 mm
    focal_length R18_Microlens_F     // 3 mm
    distance R18_d                   // d = 3 mm
  }
  sensor { pixel_size R18_Pixel }    // 24 mm across
  samples 64
  radiometry irradiance             // what the sensor receives (docs/camera.md)
}
