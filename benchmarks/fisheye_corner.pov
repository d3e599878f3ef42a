// SPDX-License-Identifier: AGPL-3.0-or-later
// A small crop at the corner of the Lytro-class sensor behind the fisheye, for counting what aimed
// samples cost where the pupil bounds cut cat's eyes with four cutting discs (BENCHMARKS.md,
// "Samples where light passes"): 7728 x 5368 pixels of 1.4 um would put the corner pixel 5.41 mm
// and 3.76 mm from the axis; the sensor is moved so that a 64 x 48 render is the 64 x 48 pixels
// in that corner. Hexagonal 20 um microlenses matched to the fisheye's working f-number at this
// focus (4.006: f = 80.1 um), d = f. From the repository root:
//   tools/compare-instructions OLD/povray NEW/povray --size 64x48 --library scenes --library lenses \
//       --scene "fisheye corner=benchmarks/fisheye_corner.pov"
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"
camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  mm_per_unit 1000
  main_lens {
    lens_file "fisheye_10mm_muller_f4.dat"
    f_number 4
    focus_distance Scene_Focus
  }
  microlens_array {
    hexagonal
    pitch 0.020
    focal_length 0.0801
    distance 0.0801
  }
  sensor {
    pixel_size 0.0014
    offset <5.3648, 3.7240>          // ((7728 - 64) / 2, (5368 - 48) / 2) pixels
  }
  samples 16
}
