// SPDX-License-Identifier: AGPL-3.0-or-later
// realistic_raw.pov: a Lytro-class raw with the realism switched on (docs/worked-examples.md,
// section 3): a real multi-element main lens traced surface by surface, f-number-matched
// hexagonal microlenses, the cos^4 law with the pixels' angular response, diffraction by the
// microlenses, a 10-bit Bayer read-out with shot, dark, read and fixed-pattern noise, and the
// white image that a decoder devignettes with.
//
//   main lens   lenses/wide_angle_22mm_laikin_f3.5.dat (Laikin, Lens Design, table 8.1):
//               EFL 22.01 mm, used at f/4, focused at 2 m (the sphere of plenoptic_scene.inc)
//   microlenses hexagonal, pitch 100 um, f = 400 um = 4 x pitch: matched to the lens's working
//               f-number at this focus (4.02, main_lens.paraxial.working_f_number), d = f
//   sensor      7 um pixels, 1544 x 1072 of them: the Illum's 10.8 x 7.5 mm and its microimages
//               of about 14.3 px, with pixels and microlenses 5 times the Illum's (108 x 86
//               microlenses instead of about 540 x 430), so that the render takes minutes;
//               GRBG mosaic, 10 bits, black level 64, 4500 e- full well
//
// Render from the repository root (the lens file is found in lenses/):
//   build/povray +Iscenes/realistic_raw.pov +Lscenes +Orealistic_raw.png +W1544 +H1072
// It writes realistic_raw.png (the noise-free picture, the ground truth),
// realistic_raw.raw.png (the camera's raw in DN: 16-bit grey PNG of 10-bit values, a GRBG
// mosaic), realistic_raw.white.png (the white image, also in DN),
// realistic_raw.microimages.csv (every microimage's true centre: behind a real lens they leave
// the lattice) and realistic_raw.plenoptic.json. Decode the raw, devignetted by the white image:
//   tools/plenoptic-decode realistic_raw.raw.png --white realistic_raw.white.png \
//       --out realistic_raw.lightfield --contact-sheet realistic_raw.contact-sheet.png

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location            // the lens's front vertex
  look_at  Scene_Look_At
  mm_per_unit 1000                   // the scene is in metres
  main_lens {
    lens_file "wide_angle_22mm_laikin_f3.5.dat"
    f_number 4                       // the stop sized so that EFL / entrance pupil = 4
    focus_distance Scene_Focus       // 2 m from the front vertex: the sphere
  }
  microlens_array {
    hexagonal
    pitch 0.100                      // mm
    focal_length 0.400               // mm: f / p = 4, the lens's working f-number
    distance 0.400                   // d = f: plenoptic 1.0
  }
  sensor {
    pixel_size 0.007                 // mm
    angular_response 32              // on-chip microlenses: light at angle t counts cos^32(t)
    bayer grbg                       // Lytro's raws are GRBG
    bit_depth 10
    black_level 64
    full_well 4500
    exposure 3000                    // electrons of a pixel whose noise-free value is 1
    read_noise 3
    dark_current 10 exposure_time 0.02
    prnu 0.01 dsnu 1.5
    seed 1
  }
  radiometry irradiance              // the cos^4 law; needed by angular_response
  diffraction                        // the microlenses' Airy pattern at 610, 550, 465 nm
  white_image                        // realistic_raw.white.png: a white world, same read-out
  samples 16
}
