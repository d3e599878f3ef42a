// SPDX-License-Identifier: AGPL-3.0-or-later
// The README's demo: a plenoptic 1.0 camera (microlenses focused at infinity, d = f)
// looking at objects between 1.2 m and 4 m, focused at 2 m.
//   build/povray +Iscenes/demo.pov +Odemo-output/demo.png +W1000 +H750
// gives the raw lenslet image, demo.plenoptic.json (ground truth) and, with depth_map,
// demo.depth.exr. tools/plenoptic-decode turns them into views and a contact sheet.
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "colors.inc"
#include "textures.inc"

camera {
  plenoptic
  location <0, 0.5, -2>
  look_at  <0, 0.3, 0>
  mm_per_unit 1000                 // one scene unit is one metre
  main_lens {
    thin_lens
    focal_length 16                // mm
    f_number 4                     // matches the microlenses: pitch / d = 0.15 / 0.6 = 1/4
    focus_distance 2               // scene units (m) in front of the lens
  }
  microlens_array {
    hexagonal
    pitch 0.15                     // mm: 15 pixels of 10 um
    focal_length 0.6               // mm
    distance 0.6                   // d = f: plenoptic 1.0
  }
  sensor { pixel_size 0.01 }       // mm; the pixel count is +W/+H
  samples 16
  depth_map
}

light_source { <-3, 5, -4> color rgb 1.1 }
light_source { < 4, 3, -2> color rgb 0.4 shadowless }
sky_sphere { pigment { gradient y color_map { [0 rgb <0.75, 0.85, 1>] [1 rgb <0.3, 0.45, 0.8>] } } }

plane { y, 0 pigment { checker color rgb 0.9 color rgb 0.25 scale 0.2 } finish { diffuse 0.8 } }
// Back wall with fine text-like texture, 4 m away: out of focus.
box { <-3, 0, 2>, <3, 3, 2.05> pigment { brick color rgb <0.8, 0.75, 0.7> color rgb <0.6, 0.25, 0.15> brick_size <0.25, 0.08, 0.1> mortar 0.01 } }
// In focus (2 m from the lens): a striped sphere.
sphere { <0.05, 0.2, 0>, 0.2 pigment { gradient y color_map { [0 Red] [0.5 Red] [0.5 White] [1 White] } scale 0.1 } finish { specular 0.4 } }
// Nearer (1.2 m): a green cube; farther (3 m): a blue cylinder.
box { <-0.12, 0, -0.12>, <0.12, 0.24, 0.12> rotate y*30 translate <-0.22, 0, -0.75> pigment { checker Green White scale 0.06 } }
cylinder { <0.5, 0, 1.1>, <0.5, 0.8, 1.1>, 0.12 pigment { radial frequency 12 color_map { [0 Blue] [0.5 Blue] [0.5 Yellow] [1 Yellow] } translate <0.5, 0, 1.1> } }
