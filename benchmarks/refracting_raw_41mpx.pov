// SPDX-License-Identifier: AGPL-3.0-or-later
// The full-size refracting raw of BENCHMARKS.md "Refracting microlenses between anchors": the
// Lytro-class sensor (7728 x 5368 pixels of 1.4 um) behind the Laikin 22 mm lens at f/2.8, focused
// at 2.5 m, with hexagonal refracting microlenses of 20 um pitch: plano-convex caps of R = 0.02 mm,
// n = 1.5, 4 um thick on a 10 um substrate, the curved side to the scene (paraxial f = 0.04 mm),
// the sensor 0.031 mm behind the flat back (the set-up of plenoptic_microimage_truth
// --array 0.02 0.04 0.031 --refracting 0.02 0.004 0.01 1.5). The still life of
// scenes/plenoptic_scene.inc. Thin=1 renders the thin microlenses the caps stand for instead
// (f = d = 0.04 mm, the caps' paraxial focal length: the Lytro-class camera of BENCHMARKS.md
// "Microimage truth"). Turn (degrees) and Shift_X, Shift_Y (mm) turn the array about the axis and
// move it across (rotate <0, 0, Turn> translate <Shift_X, Shift_Y, 0>; [0]). From the repository
// root (Samples: the camera's samples [16]):
//   build/povray +Ibenchmarks/refracting_raw_41mpx.pov +Lscenes +Llenses +W7728 +H5368 \
//       +Orefracting_41mpx.png [Declare=Samples=1] [Declare=Thin=1] [Declare=Turn=0.2 ...]
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"
#ifndef (Samples) #declare Samples = 16; #end
#ifndef (Thin) #declare Thin = 0; #end
#ifndef (Turn) #declare Turn = 0; #end
#ifndef (Shift_X) #declare Shift_X = 0; #end
#ifndef (Shift_Y) #declare Shift_Y = 0; #end
camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  mm_per_unit 1000
  main_lens {
    lens_file "wide_angle_22mm_laikin_f3.5.dat"
    f_number 2.8
    focus_distance 2.5
  }
  microlens_array {
    hexagonal
    pitch 0.020
    #if (Thin)
      focal_length 0.04
      distance 0.04
    #else
      lens {
        surface { radius 0.02 }      // R, mm: paraxial f = R / (n - 1) = 0.04 mm
        thickness 0.004
        ior 1.5
        substrate 0.01
      }
      distance 0.031                 // the caps' back focal distance, mm
    #end
    rotate <0, 0, Turn>
    translate <Shift_X, Shift_Y, 0>
  }
  sensor { pixel_size 0.0014 }
  samples Samples
}
