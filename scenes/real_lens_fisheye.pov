// SPDX-License-Identifier: AGPL-3.0-or-later
// real_lens_fisheye.pov: a real main lens (docs/real-lenses.md): the 10 mm f/4 fisheye of
// lenses/fisheye_10mm_muller_f4.dat (Muller, US 4,525,038; Smith, Modern Lens Design p. 164),
// traced surface by surface at f/5.6 on a 30 x 30 mm sensor (render +W300 +H300), no array:
// the whole image circle, about f times the field angle (13.3 mm at 76 degrees), inside a
// checkered room; the printed clear apertures end the field about 76.9 degrees from the axis
// (the front element's rim), a degree short of the printed 155.9 degree field.
// location is the front vertex of the lens.
#version 3.7;
global_settings { assumed_gamma 1 }
camera { plenoptic
  location <0, 1.2, 0> look_at <0, 1.2, 1>
  main_lens { lens_file "fisheye_10mm_muller_f4.dat" f_number 5.6 focus_distance 1.5 }
  sensor { pixel_size <0.1, 0.1> }
  samples 16
}
plane { y, 0 pigment { checker rgb 1 rgb 0.1 scale 0.5 } finish { ambient 1 diffuse 0 } }
plane { y, 3 pigment { checker rgb <0.6,0.8,1> rgb 0.3 scale 0.5 } finish { ambient 1 diffuse 0 } }
plane { z, 2 pigment { checker rgb <1,0.5,0.2> rgb 0.2 scale 0.5 } finish { ambient 1 diffuse 0 } }
plane { x, -2 pigment { checker rgb <0.2,1,0.4> rgb 0.2 scale 0.5 } finish { ambient 1 diffuse 0 } }
plane { x, 2 pigment { checker rgb <1,0.2,0.3> rgb 0.2 scale 0.5 } finish { ambient 1 diffuse 0 } }
