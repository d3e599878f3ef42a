// SPDX-License-Identifier: AGPL-3.0-or-later
// chief_ray_plenoptic.pov: a thin main lens and an array of pinholes in front of the
// sensor: the chief-ray model of a plenoptic camera. Every pixel receives light along one
// ray only, the one through the centre of its pinhole, so each pixel is an exact sample
// of one position (the pinhole) and one direction (where its ray crosses the main lens):
// the idealised plenoptic 1.0 camera of the textbooks, without microlens blur. Each
// microimage is the image of the main lens's aperture seen through its pinhole; where the
// scene is in focus (the sphere, the floor at 2 m) every pixel of a microimage looks at
// the same point and the microimage is flat; elsewhere it holds a tiny picture of the
// out-of-focus scene (the cube, the wall), which is what makes refocusing possible.
//
// Numbers: a 16 mm f/4 main lens focused at 2 m (D = 1 / (1/16 - 1/2000) = 16.13 mm, A =
// 4 mm), pinholes on a hexagonal grid of pitch 0.15 mm (15 pixels of 10 um), d = 0.6 mm in
// front of the sensor. The image-side f-numbers match (D / A = 4.03, d / p = 4), so the
// microimages, discs A d / D = 0.149 mm = 14.9 px across, spaced p (D + d) / D = 15.6 px,
// nearly touch without overlapping.
//
// Render from the repository root (8 x 6 mm of sensor, about 51 x 44 microimages):
//   build/povray +Iscenes/chief_ray_plenoptic.pov +Lscenes +Ochief_ray_plenoptic.png +W800 +H600
// Beside the image: chief_ray_plenoptic.plenoptic.json (microimage centres, LFToolbox grid).

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  main_lens {
    thin_lens
    focal_length 16                  // mm
    f_number 4                       // A = 4 mm
    focus_distance Scene_Focus       // 2 m: sets D = 16.13 mm
  }
  microlens_array {
    hexagonal
    pitch 0.15                       // mm
    pinhole
    distance 0.6                     // d, mm
  }
  sensor { pixel_size 0.01 }
  samples 16                         // pixel area x main-lens aperture
}
