// SPDX-License-Identifier: AGPL-3.0-or-later
// real_lens_double_gauss.pov: a real main lens (docs/real-lenses.md): the 50 mm f/2 double-Gauss
// of lenses/double_gauss_50mm_tronnier_f2.dat (Tronnier, US 2,673,491; Smith, Modern Lens Design
// p. 312), traced surface by surface near full aperture on a 36 x 24 mm sensor (render
// +W480 +H320), no array: shallow depth of field (focused on the sphere 2.5 m away; the wall
// behind and the floor in front blur), the vignetting of the clear apertures in the corners.
// f_number 2.1: with its printed clear apertures surface 3's rim cuts the axial beam before the
// stop at f/2.073 focused at infinity, about f/2.06 at 2.5 m (lenses/README.md), so the printed f/2
// is refused.
// location is the front vertex of the lens.
#version 3.7;
global_settings { assumed_gamma 1 }
camera { plenoptic
  location <0, 0.5, -2.5> look_at <0, 0.5, 0>
  main_lens { lens_file "double_gauss_50mm_tronnier_f2.dat" f_number 2.1 focus_distance 2.5 }
  sensor { pixel_size <0.075, 0.075> }
  samples 16
}
plane { y, 0 pigment { checker rgb 1 rgb 0.1 scale 0.25 } finish { ambient 1 diffuse 0 } }
plane { z, 2.5 pigment { checker rgb <1,0.5,0.2> rgb 0.2 scale 0.25 } finish { ambient 1 diffuse 0 } }
sphere { <0, 0.5, 0>, 0.3 pigment { checker rgb <0.2,0.4,1> rgb 1 scale 0.1 } finish { ambient 1 diffuse 0 } }
