// SPDX-License-Identifier: AGPL-3.0-or-later
// The cost of aspheres (BENCHMARKS.md, "Conic and aspheric surfaces"): the benchmark scene through
// a made-up 53 mm triplet at f/5.6, all spherical, or (Declare=ASPH=1) with a conic on its first
// surface and r^4, r^6 terms on its last. Render from the repository root:
//   build/povray +Ibenchmarks/asphere_triplet.pov +Lbenchmarks +W320 +H240 -D [Declare=ASPH=1]
#version 3.7;
global_settings { assumed_gamma 1 }
#include "scene.inc"
#ifndef (ASPH) #declare ASPH = 0; #end
camera { plenoptic location <0, 0.6, -2.5> look_at <0, 0.4, 0>
  main_lens { prescription {
    surface { radius 30 thickness 6 ior 1.6 aperture 24 #if (ASPH) conic -0.6 #end }
    surface { radius -200 thickness 4 ior 1 aperture 24 }
    stop { thickness 4 aperture 10 }
    surface { radius -40 thickness 2 ior 1.6 aperture 14 }
    surface { radius 60 thickness 4 ior 1 aperture 14 }
    surface { radius 100 thickness 5 ior 1.6 aperture 18 }
    surface { radius -40 thickness 0 ior 1 aperture 18 #if (ASPH) aspheric <2e-6, -1e-9> #end } }
    f_number 5.6 focus_distance 2.5 }
  sensor { pixel_size 0.06 }
  samples 16
}
