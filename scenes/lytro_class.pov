// SPDX-License-Identifier: AGPL-3.0-or-later
// lytro_class.pov: a plenoptic 1.0 camera with the parameters of a Lytro-class consumer
// light-field camera (second generation, "Illum" class). Where each number comes from, and
// how good it is, is in docs/worked-examples.md; in short:
//   sensor      7728 x 5368 pixels of 1.4 um (10.8 x 7.5 mm, "40 megarays", 1/1.2 inch)
//   main lens   F = 9.98 mm (near the wide end of the 9.5-77.8 mm zoom), constant f/2
//   microlenses hexagonal, pitch 20 um (14.3 pixels), f = 40.1 um (f/2), d = f
// Derived (thin-lens model): focused at 2 m, D = 10.030 mm; microimage centres 14.34 px
// apart, microimages 14.2 px across (the aperture's image: A d / D); about 539 x 432
// microlenses over the sensor; horizontal field of view of the whole sensor 56.7 degrees.
//
// Render from the repository root. The pixel count is the sensor's, so +W/+H choose how
// much of the sensor to render around its centre:
//   whole sensor (41 Mpx, slow):  +W7728 +H5368
//   a quarter of each side:       +W1932 +H1342   (15.4 degrees across, 135 x 108 microimages)
//   build/povray +Iscenes/lytro_class.pov +Lscenes +Olytro_class.png +W1932 +H1342
// Beside the image: lytro_class.plenoptic.json; its lftoolbox_lenslet_grid_model block is
// what LFToolbox's decoder wants in place of a white-image calibration.
//
// A first-generation Lytro is the same design on a smaller sensor: 3280 x 3280 pixels of
// 1.4 um, microimages about 10 pixels across (pitch about 14 um), an f/2 zoom lens. For it,
// use pitch 0.014, focal_length 0.028, distance 0.028 and render +W3280 +H3280 (the
// numbers are approximate: see docs/worked-examples.md).

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  mm_per_unit 1000                   // the scene is in metres
  main_lens {
    thin_lens
    focal_length 9.98                // mm
    f_number 2                       // A = 4.99 mm
    focus_distance Scene_Focus       // 2 m: D = 1 / (1/9.98 - 1/2000) = 10.030 mm
  }
  microlens_array {
    hexagonal
    pitch 0.020                      // mm
    focal_length 0.040               // mm: f / p = 2, matched to the f/2 main lens
    distance 0.040                   // d = f: plenoptic 1.0
  }
  sensor { pixel_size 0.0014 }       // 1.4 um
  samples 16
}
