// SPDX-License-Identifier: AGPL-3.0-or-later
// focused2.pov: the focused ("plenoptic 2.0", Raytrix-type, Keplerian) light-field camera.
// The main lens forms its image of the scene a few millimetres in front of the microlens
// array, and the microlenses are focused on that image (d != f): each microimage is a small,
// sharp, inverted picture of a patch of the main lens's image, and neighbouring microimages
// repeat the same detail shifted. How far a detail moves from one microimage to the next
// says how far in front of the array its image lies, hence its depth (the "virtual depth").
//
// Numbers: 16 mm main lens at D = 20.63 mm from the array (it images 2 m at
// b = 1 / (1/16 - 1/2000) = 16.13 mm, 4.5 mm in front of the array); hexagonal microlenses
// of pitch 0.3 mm (30 pixels of 10 um), f = 0.75 mm, d = 0.9 mm. A microlens is sharp on
// an image a = 1 / (1/f - 1/d) = 4.5 mm in front of it, with magnification d / a = 0.2:
// each microimage shows a 1.5 mm patch of the main lens's image, and every scene point
// appears in about (A a / b) / p = (5.71 x 4.5 / 16.13) / 0.3 = 5.3 microimages across.
// f/2.8 (A = 5.71 mm) keeps the microimages apart: at f/2.3, where D / A would equal d / p,
// the blur of the defocused aperture image would make neighbours overlap (the camera warns).
// Everything from 1.35 m to 5 m images within 0.1 mm of the plane the microlenses are
// focused on, so the whole scene is nearly sharp, each depth with its own repetition.
//
// Render from the repository root:
//   build/povray +Iscenes/focused2.pov +Lscenes +Ofocused2.png +W900 +H720
// Beside the image: focused2.plenoptic.json.

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
    f_number 2.8                     // A = 5.71 mm
    distance 20.63                   // D, mm: the array sits 4.5 mm behind the image of 2 m
  }
  microlens_array {
    hexagonal
    pitch 0.3                        // mm, 30 pixels
    focal_length 0.75                // f, mm
    distance 0.9                     // d != f: focused on a plane 4.5 mm in front
  }
  sensor { pixel_size 0.01 }
  samples 16
}
