// SPDX-License-Identifier: AGPL-3.0-or-later
// real_lens_telephoto.pov: a real main lens (docs/real-lenses.md): the 250 mm F/5.6 telephoto of
// lenses/telephoto_250mm_sigler_f5.6.dat (Sigler; Smith, Modern Lens Design p. 175), traced
// surface by surface at its printed stop (f/5.42) on a 36 x 24 mm sensor (render +W480 +H320),
// no array: a narrow field (8.2 x 5.5 degrees) and a compressed perspective, focused on the
// middle of three spheres 10, 12 and 14 m away.
// location is the front vertex of the lens.
#version 3.7;
global_settings { assumed_gamma 1 }
camera { plenoptic
  location <0, 0.5, -12> look_at <0, 0.5, 0>
  main_lens { lens_file "telephoto_250mm_sigler_f5.6.dat" focus_distance 12 }
  sensor { pixel_size <0.075, 0.075> }
  samples 16
}
plane { y, 0 pigment { checker rgb 1 rgb 0.1 scale 0.25 } finish { ambient 1 diffuse 0 } }
plane { z, 6 pigment { checker rgb <1,0.5,0.2> rgb 0.2 scale 0.25 } finish { ambient 1 diffuse 0 } }
sphere { <-0.5, 0.35, -2>, 0.35 pigment { checker rgb <0.2,0.4,1> rgb 1 scale 0.1 } finish { ambient 1 diffuse 0 } }
sphere { <0, 0.35, 0>, 0.35 pigment { checker rgb <0.2,1,0.4> rgb 1 scale 0.1 } finish { ambient 1 diffuse 0 } }
sphere { <0.5, 0.35, 2>, 0.35 pigment { checker rgb <1,0.2,0.3> rgb 1 scale 0.1 } finish { ambient 1 diffuse 0 } }
