// SPDX-License-Identifier: AGPL-3.0-or-later
// traced_errors.pov: what manufacturing errors cost behind a traced main lens (BENCHMARKS.md,
// "Real microlens arrays: what the figures say"). The camera of scenes/realistic_raw.pov without
// its read-out (the Laikin 22 mm wide angle at f/4, hexagonal thin microlenses of pitch 100 um,
// f = d = 400 um, 7 um pixels), 16 samples, and with Declare=ERR=1 the arrays section's errors:
// position 2 um (1 um along the axis), focal length 2 %, rotation 1 degree. The microimage truth is
// off: only the render is counted.
//   valgrind --tool=callgrind build/povray +Ibenchmarks/traced_errors.pov +Lscenes +Llenses +W64 +H48 -D -P -F +WT1 -GA [Declare=ERR=1]

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  mm_per_unit 1000
  main_lens {
    lens_file "wide_angle_22mm_laikin_f3.5.dat"
    f_number 4
    focus_distance Scene_Focus
  }
  microlens_array {
    hexagonal
    pitch 0.100
    focal_length 0.400
    distance 0.400
#ifndef (ERR) #declare ERR = 0; #end
#if (ERR)
    errors { position 0.002 0.001 focal_length 0.02 rotation 1 seed 1 }
#end
  }
  sensor { pixel_size 0.007 }
  microimage_centres off
  samples 16
}
