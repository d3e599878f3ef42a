// SPDX-License-Identifier: AGPL-3.0-or-later
// refracting_microlenses.pov: focused2.pov's camera with real microlenses: plano-convex caps of
// glass (n = 1.5, radius 0.375 mm: paraxial focal length R / (n - 1) = 0.75 mm) on a 0.25 mm
// substrate, the caps facing the main lens, traced exactly (Snell's law at the cap and at the
// flat back, total internal reflection, the cap's clear aperture its hexagonal cell). Their
// spherical aberration softens the microimages' rims and moves light within them; compare with
// focused2.pov's ideal thin lenses.
//
// Numbers: the array's plane is its flat back (the face nearest the sensor), from which d is
// measured and at which D ends. The glass is t + T = 0.3 mm thick; the thick lens's principal
// planes lie at its cap's vertex (0.3 mm in front of the back) and L/n = 0.2 mm in front of the
// back. To be focused like focused2.pov (0.9 mm behind the rear principal plane, on an image
// 4.5 mm in front of the front one), d = 0.9 - 0.2 = 0.7 mm and the main lens's image of 2 m
// (16.13 mm behind it) lies 4.5 + 0.3 mm in front of the back: D = 16.13 + 4.8 = 20.93 mm.
// The cap rises 0.042 mm over its cell's corners (sag of R = 0.375 mm at p / sqrt(3) = 0.173 mm),
// within its 0.05 mm thickness, as the camera requires.
//
// Render from the repository root:
//   build/povray +Iscenes/refracting_microlenses.pov +Lscenes +Orefracting_microlenses.png +W900 +H720
// Beside the image: refracting_microlenses.plenoptic.json (microlens_array.refracting: the shape
// and the paraxial focal length and principal planes).

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
    distance 20.93                   // D, mm: to the array's flat back
  }
  microlens_array {
    hexagonal
    pitch 0.3                        // mm, 30 pixels
    lens {
      surface { radius 0.375 }       // R, mm: the cap, convex towards the scene
      thickness 0.05                 // t: the cap's centre thickness, mm
      ior 1.5                        // n
      substrate 0.25                 // T, mm
      curved_side scene              // the default
    }
    distance 0.7                     // d, mm: flat back -> sensor
  }
  sensor { pixel_size 0.01 }
  samples 16
}
