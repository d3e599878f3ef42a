// SPDX-License-Identifier: AGPL-3.0-or-later
// The README's demo: a plenoptic 1.0 camera (microlenses focused at infinity, d = f) with a
// 50 mm f/2 main lens focused at 1.5 m, looking at small objects from 0.9 m to 4 m.
//   build/povray +Iscenes/demo.pov +Odemo-output/demo.png +W1200 +H900
// writes the raw lenslet image, demo.plenoptic.json (ground truth) and demo.depth.exr;
// tools/plenoptic-decode turns them into sub-aperture views and a contact sheet.
// Outer views see the near cube and the far wall shifted by about 2 lenses either way.
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "colors.inc"

camera {
  plenoptic
  location <0, 0.12, -1.5>
  look_at  <0, 0.06, 0>
  mm_per_unit 1000                 // one scene unit is one metre
  main_lens {
    thin_lens
    focal_length 50                // mm
    f_number 2                     // matches the microlenses: pitch / d = 0.15 / 0.3 = 1/2
    focus_distance 1.5             // scene units (m) in front of the lens
  }
  microlens_array {
    hexagonal
    pitch 0.15                     // mm: 15 pixels of 10 um
    focal_length 0.3               // mm
    distance 0.3                   // d = f: plenoptic 1.0
  }
  sensor { pixel_size 0.01 }       // mm; the pixel count is +W/+H (12 x 9 mm at 1200 x 900)
  samples 16
  depth_map
}

light_source { <-2, 4, -4> color rgb 1.1 }
light_source { < 3, 2, -2> color rgb 0.4 shadowless }
sky_sphere { pigment { gradient y color_map { [0 rgb <0.75, 0.85, 1>] [1 rgb <0.3, 0.45, 0.8>] } } }

plane { y, 0 pigment { checker color rgb 0.9 color rgb 0.25 scale 0.05 } }
// 4 m from the lens: a brick wall, out of focus behind.
box { <-2, 0, 2.5>, <2, 2, 2.55> pigment { brick color rgb <0.85, 0.8, 0.75> color rgb <0.6, 0.25, 0.15> brick_size <0.12, 0.04, 0.1> mortar 0.008 } }
// 1.5 m, in focus: a striped sphere.
sphere { <0, 0.06, 0>, 0.06 pigment { gradient y color_map { [0 Red] [0.5 Red] [0.5 White] [1 White] } scale 0.03 } finish { specular 0.4 } }
// 0.9 m, in front of the focus: a green checkered cube.
box { <-0.025, 0, -0.025>, <0.025, 0.05, 0.025> rotate y * 30 translate <-0.07, 0, -0.6> pigment { checker Green White scale 0.0125 } }
// 2.5 m, behind the focus: a blue and yellow post.
cylinder { <0.13, 0, 1>, <0.13, 0.3, 1>, 0.03 pigment { radial frequency 8 color_map { [0 Blue] [0.5 Blue] [0.5 Yellow] [1 Yellow] } translate <0.13, 0, 1> } }
