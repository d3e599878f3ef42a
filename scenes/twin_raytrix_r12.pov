// SPDX-License-Identifier: AGPL-3.0-or-later
// twin_raytrix_r12.pov: a digital twin of the Raytrix R12 of the data sets R12-A, R12-B and R12-C
// (docs/digital-twins.md): the camera COMPOTE's published calibration of R12-A describes, behind
// the catalogue's real double-Gauss 50 mm lens, with the data sets' checkerboards and their white
// images at N = 4, 5.66, 8, 11.31 and 16.
//
// Sources of the numbers:
//   - COMPOTE (comsee-research/compote), examples/config/intrinsics.js, the calibration of the
//     setting R12-A: main lens f 49.885 mm at "aperture" 4, D = 56.860 mm (main lens -> array),
//     d = 0.33713 mm (array -> sensor), hexagonal pitch 0.12744 mm, three microlens focal lengths
//     0.58267 / 0.52402 / 0.56057 mm, sensor 4080 x 3068 of 0.0055 mm ("scale");
//   - the data sets' description (comsee-research/plenoptic-datasets, README.md): a Raytrix R12
//     with a Nikon AF Nikkor 50 mm f/1.8D, focus h = 450 mm (R12-A), 1000 mm (R12-B), infinity
//     (R12-C); white images at N in {4, 5.66, 8, 11.31, 16}; checkerboards 9 x 5 of 10 mm (A),
//     8 x 5 of 20 mm (B), 7 x 5 of 30 mm (C).
//
// The main lens: lenses/double_gauss_50mm_tronnier_f2.dat (EFL 50.358 mm), stopped to f/4, in
// place of the Nikkor (whose prescription is not published). Its paraxial data decides where
// the array goes: R12-A keeps COMPOTE's calibrated D = 56.86 mm, measured from the lens's rear
// principal plane (14.252 mm in front of its rear vertex): `distance 42.608` (rear vertex ->
// array). That focuses the lens 440.4 mm in front of its front principal plane, 417.2 mm from
// its front vertex, not at the nominal h = 450 mm: the 450 mm of the data set is the focus ring's
// setting, which no thin lens of f 49.885 at D = 56.86 reproduces either (it gives 407 mm).
// R12-B and R12-C have no published calibration: their arrays are placed where the lens
// focuses h (1000 mm from the front vertex; infinity: the back focal distance).
//
// Declarations (a data-set spec sets them; defaults in brackets):
//   Twin_Setting    1: R12-A [1], 2: R12-B, 3: R12-C (array position and checkerboard)
//   Twin_F_Number   the aperture the picture is taken at [4]
//   Twin_Main_Lens  1: the double-Gauss traced [1]; 2: its thick-lens equivalent (thick_lens);
//                   3: a thin lens of its paraxial numbers (twin_raytrix_r12_camera.inc, which
//                   holds the camera, says which; docs/digital-twins.md, "Exporting the twins")
//   Twin_Board_RX, Twin_Board_RY, Twin_Board_RZ, Twin_Board_Scale: the board's rotation
//                   (degrees, x then y then z) and its distance from the front vertex as a
//                   multiple of the setting's [-0.5, 17.2, -3.6 and 1: one of the R12-A poses of
//                   COMPOTE's examples/config/poses.js (frame 10), at 0.30 m for R12-A; B and C:
//                   the distance scaled with the square, 0.60 m and 0.90 m]
//   Dataset_Samples [16], Dataset_White_Image [1]: white images at the five f-numbers, beside
//                   the image: <stem>.white.f4.png ... <stem>.white.f16.png
//   Dataset_Depth_Map [0]: also the depth and virtual depth maps
//
// Full size (12.5 Mpx; its time is a benchmark's, docs/digital-twins.md):
//   build/povray +Iscenes/twin_raytrix_r12.pov +Lscenes +Llenses +Otwin_r12.png +W4080 +H3068
// A crop around the sensor's centre (+W/+H pick the pixels, the sensor's pitch stays):
//   build/povray +Iscenes/twin_raytrix_r12.pov +Lscenes +Llenses +Otwin_r12.png +W480 +H360
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "calibration_targets.inc"

#include "twin_raytrix_r12_camera.inc"            // the camera (Twin_Setting, Twin_F_Number, Twin_Main_Lens, Dataset_*)

#ifndef (Twin_Board_RX) #declare Twin_Board_RX = -0.5; #end
#ifndef (Twin_Board_RY) #declare Twin_Board_RY = 17.2; #end
#ifndef (Twin_Board_RZ) #declare Twin_Board_RZ = -3.6; #end
#ifndef (Twin_Board_Scale) #declare Twin_Board_Scale = 1; #end
#declare Twin_Board_Distance = Twin_Board_Scale * select(Twin_Setting - 2, 0.30, 0.60, 0.90);

background { rgb 0.2 }
object {
  #switch (Twin_Setting)
    #case (1) Plenoptic_Checkerboard(5, 9, 0.010, rgb 0.9, rgb 0.05) #break
    #case (2) Plenoptic_Checkerboard(5, 8, 0.020, rgb 0.9, rgb 0.05) #break
    #case (3) Plenoptic_Checkerboard(5, 7, 0.030, rgb 0.9, rgb 0.05) #break
  #end
  rotate <Twin_Board_RX, Twin_Board_RY, Twin_Board_RZ>
  translate <0, 0, Twin_Board_Distance>
}
