// SPDX-License-Identifier: AGPL-3.0-or-later
// real_lens_wide_angle.pov: a real main lens (docs/real-lenses.md): the 22 mm f/3.5
// inverted telephoto of lenses/wide_angle_22mm_laikin_f3.5.dat (Laikin, Lens Design, table 8.1),
// traced surface by surface at f/5.6 on a 28.8 x 19.2 mm sensor (render +W480 +H320), no array:
// barrel distortion and the mechanical vignetting of the clear apertures towards the corners.
// location is the front vertex of the lens.
#version 3.7;
global_settings { assumed_gamma 1 }
camera { plenoptic
  location <0, 1, -4> look_at <0, 0.5, 0>
  main_lens { lens_file "wide_angle_22mm_laikin_f3.5.dat" f_number 5.6 focus_distance 4 }
  sensor { pixel_size <0.06, 0.06> }
  samples 16
}
plane { y, 0 pigment { checker rgb 1 rgb 0.1 scale 0.5 } finish { ambient 1 diffuse 0 } }
plane { z, 3 pigment { checker rgb <1,0.5,0.2> rgb 0.2 scale 0.5 } finish { ambient 1 diffuse 0 } }
