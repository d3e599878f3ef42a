// SPDX-License-Identifier: AGPL-3.0-or-later
// The full-size realistic raw of BENCHMARKS.md "The realistic raw, stage by stage": the
// Lytro-class camera (7728 x 5368 pixels of 1.4 um, hexagonal 20 um microlenses at f/3.5, d = f)
// behind the Laikin 22 mm lens at f/3.5, with every part of the realism a user would switch on:
// irradiance radiometry with an angular response of 32, diffraction, a GRBG 10-bit read-out with
// noise, and the white image. The still life of scenes/plenoptic_scene.inc. From the repository
// root (Samples: the camera's samples [16]):
//   build/povray +Ibenchmarks/realistic_raw_41mpx.pov +Lscenes +Llenses +W7728 +H5368 \
//       +Orealistic_41mpx.png [Declare=Samples=1]
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"
#ifndef (Samples) #declare Samples = 16; #end
camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  mm_per_unit 1000
  main_lens {
    lens_file "wide_angle_22mm_laikin_f3.5.dat"
    f_number 3.5
    focus_distance Scene_Focus
  }
  microlens_array {
    hexagonal
    pitch 0.020
    focal_length 0.070               // f/3.5, matched to the main lens
    distance 0.070                   // d = f: plenoptic 1.0
  }
  sensor {
    pixel_size 0.0014
    angular_response 32
    bayer grbg
    bit_depth 10
    black_level 64
    full_well 4500
    exposure 3000
    read_noise 3
    dark_current 10 exposure_time 0.02
    prnu 0.01 dsnu 1.5
    seed 1
  }
  radiometry irradiance
  diffraction
  white_image
  samples Samples
}
