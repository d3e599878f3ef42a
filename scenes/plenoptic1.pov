// SPDX-License-Identifier: AGPL-3.0-or-later
// plenoptic1.pov: the standard ("plenoptic 1.0", Lytro-type) light-field camera: a thin
// main lens focused on the scene, an array of thin microlenses one focal length in front
// of the sensor (d = f). Each microlens is focused at infinity, i.e. on the main lens, so
// each microimage is a sharp image of the main lens's aperture and every pixel under a
// microlens records one direction of the light that reaches that microlens. The raw image
// looks like a mosaic of small discs: flat discs where the scene is in focus (the sphere
// and the floor at 2 m), discs holding a tiny inverted picture where it is not (the cube
// at 1.35 m, the wall at 5 m). tools/plenoptic-decode turns it into sub-aperture views
// of one pixel per microlens (49 x 43 at 800 x 600), seen from 13 x 13 points of the
// main lens's aperture, and refocuses them.
//
// Numbers: 16 mm f/4 main lens focused at 2 m (D = 16.13 mm, A = 4 mm); hexagonal
// microlenses of pitch 0.15 mm and focal length f = 0.6 mm (f/4) at d = f = 0.6 mm; 10 um
// pixels. The f-numbers match (main lens, image side: D / A = 4.03; microlenses: f / p =
// 4), so the microimages, A d / D = 14.9 px across, fill their 15.6 px cells without
// overlapping. Compare chief_ray_plenoptic.pov: the same camera with pinholes.
//
// Render from the repository root:
//   build/povray +Iscenes/plenoptic1.pov +Lscenes +Oplenoptic1.png +W800 +H600
// Beside the image: plenoptic1.plenoptic.json (microimage centres, LFToolbox grid) and,
// with depth_map below, plenoptic1.depth.exr (distance along each pixel's chief ray).

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  main_lens {
    thin_lens
    focal_length 16                  // F, mm
    f_number 4                       // A = 4 mm
    focus_distance Scene_Focus       // 2 m: D = 1 / (1/16 - 1/2000) = 16.13 mm
  }
  microlens_array {
    hexagonal
    pitch 0.15                       // mm, 15 pixels
    focal_length 0.6                 // f, mm
    distance 0.6                     // d = f: plenoptic 1.0
  }
  sensor { pixel_size 0.01 }         // 10 um
  samples 16                         // pixel area x microlens cell
  depth_map                          // also write plenoptic1.depth.exr
}
