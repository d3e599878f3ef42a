// SPDX-License-Identifier: AGPL-3.0-or-later
// multifocus2.pov: a multi-focus focused plenoptic camera (Raytrix-type): three kinds of
// microlens, interleaved so that no two neighbours are alike, each focused on a different
// depth range. The scene is the usual still life made a 1:10 model (mm_per_unit 100: one
// scene unit is 100 mm), so the objects stand 135 mm (cube) to 500 mm (wall) from the lens
// and their images spread over 1.6 mm behind it: enough for the three lens types to matter.
// In the raw image the cube is sharp in one microimage in three, the sphere and the star
// in another, the column and the wall in the third; the others show the same detail blurred.
//
// Numbers (all mm): 16 mm f/3.2 main lens with the array at D = 20.65, so that the images
// of the objects lie a = D - b in front of the array: b = 16 z / (z - 16) gives a = 2.5
// (cube, z = 135), 3.26 (sphere, 200), 3.56 (star, 250), 3.88 (column, 350), 4.12 (wall,
// 500). The sensor is d = 0.9 behind the array; a microlens of focal length f is sharp on
// a = 1 / (1/f - 1/d): the types f = 0.669, 0.707, 0.738 are sharp at a = 2.6, 3.3, 4.1.
// Lens type (metadata: lens_type_rule): type(k, l) = (k - l) mod 3 in skew indices, so the
// types form three interleaved hexagonal sub-lattices. f/3.2 keeps the microimages of the
// most defocused type inside their cells.
//
// Render from the repository root:
//   build/povray +Iscenes/multifocus2.pov +Lscenes +Omultifocus2.png +W900 +H720
// Beside the image: multifocus2.plenoptic.json (with lens_types 3 and the type rule).

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  mm_per_unit 100                    // a 1:10 model: the sphere is 200 mm away
  main_lens {
    thin_lens
    focal_length 16
    f_number 3.2
    distance 20.65                   // D: main lens -> array
  }
  microlens_array {
    hexagonal
    pitch 0.3                        // 30 pixels
    focal_lengths <0.669, 0.707, 0.738>  // sharp 2.6, 3.3 and 4.1 mm in front of the array
    distance 0.9                     // d
  }
  sensor { pixel_size 0.01 }
  samples 16
}
