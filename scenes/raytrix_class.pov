// SPDX-License-Identifier: AGPL-3.0-or-later
// raytrix_class.pov: a multi-focus plenoptic 2.0 camera with the parameters of a
// Raytrix-class industrial light-field camera (an R12 with a 50 mm lens), taken from a
// published calibration of one such camera (the COMPOTE tools of Institut Pascal; sources
// and accuracy in docs/worked-examples.md):
//   sensor      4080 x 3068 pixels of 5.5 um (22.4 x 16.9 mm)
//   main lens   F = 49.89 mm (a 50 mm f/1.8 lens), used at f/4, array at D = 56.86 mm
//   microlenses hexagonal, pitch 127.4 um (23.2 pixels), three types
//               f = 582.7, 524.0, 560.6 um, sensor d = 337.1 um behind the array
// Derived (thin-lens model): microimage centres 23.31 px apart (the calibration measured
// 23.31); the main lens is focused at 407 mm; the microlenses, with d < f, are sharp on
// images 0.80, 0.95 and 0.85 mm behind the array (virtual depths 2.37, 2.80, 2.51), i.e.
// on objects 370, 364 and 368 mm from the lens. Points between about 379 and 439 mm
// image so close to the array that too few microlenses see them to measure depth; points
// beyond 439 mm image in front of the array, where microlenses with f > d cannot focus.
//
// The scene: what such a camera is used for, a close-up of a calibration target. A card
// with 9 x 5 chequers of 10 mm (the target of the published data set for this setting)
// stands 365 mm in front of the lens, turned 35 degrees so that it spans 339 to 391 mm:
// the three lens types are sharp on different strips of it. Behind it, the shared still
// life at 1:3.3 (mm_per_unit 300; 405 mm to the cube, 600 mm to the sphere) lies beyond
// the range any lens type can focus and shows blurred, as it would in the real camera.
// The camera warns that the microimages overlap: at f/4 the most defocused lens type
// spills light through the corners of its hexagonal cell into its neighbours' (real
// microlenses are round and masked); the rim this adds is less than a pixel wide.
//
// Render from the repository root. The pixel count is the sensor's (+W/+H crop it):
//   whole sensor (12.5 Mpx):   +W4080 +H3068
//   half of each side:         +W2040 +H1534   (11.3 degrees across, 88 x 76 microimages;
//                              the card nearly fills it)
//   build/povray +Iscenes/raytrix_class.pov +Lscenes +Oraytrix_class.png +W2040 +H1534
// Beside the image: raytrix_class.plenoptic.json (lens_types 3 and the type rule).

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  mm_per_unit 300                    // one scene unit is 300 mm
  main_lens {
    thin_lens
    focal_length 49.885              // mm
    f_number 4                       // A = 12.47 mm (f-number matching would be f/2.32)
    distance 56.860                  // D, mm
  }
  microlens_array {
    hexagonal
    pitch 0.12744                    // mm
    focal_lengths <0.58267, 0.52402, 0.56057>   // mm, three interleaved types
    distance 0.33713                 // d, mm (d < f: the Galilean arrangement)
  }
  sensor { pixel_size 0.0055 }       // 5.5 um
  samples 16
}

// The calibration card, 365 mm from the lens along the view, face on to the camera, then
// turned 35 degrees about its vertical axis.
#declare Card_Distance = 365 / 300;  // scene units
#declare View = vnormalize(Scene_Look_At - Scene_Location);
#declare Square = 10 / 300;         // 10 mm chequers
box { <0, 0, 0>, <9 * Square, 5 * Square, 0.002>
  pigment { checker color rgb 0.04 color rgb 0.92 scale Square }
  finish { ambient 0.35 diffuse 0.65 }
  translate <-4.5 * Square, -2.5 * Square, 0>
  rotate y * 35
  rotate x * degrees(asin(-View.y))
  translate Scene_Location + Card_Distance * View
}
