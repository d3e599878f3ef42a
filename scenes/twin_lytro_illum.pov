// SPDX-License-Identifier: AGPL-3.0-or-later
// twin_lytro_illum.pov: a digital twin of the Lytro Illum (docs/digital-twins.md): the second
// Lytro camera's sensor and microlens array, its raw read-out (GRBG Bayer mosaic, 10 bits) and its
// white images, in front of the shared still life (plenoptic_scene.inc).
//
// Sources of the numbers (docs/worked-examples.md, section 1, grades them):
//   - sensor 7728 x 5368 pixels of 1.4 um and the microlens array (hexagonal, pitch 20 um,
//     f = 40.087 um, the sensor f behind it, 541 x 434 lenses): the example camera of Institut
//     Pascal's plenoptic raw-image simulator PRISM (comsee-research/prism, examples/camera.js,
//     "scale" 0.0014, mla pitch 0.02, focal_lengths 0.040087372, mla at 9.847916 mm and the
//     sensor at 9.888004 mm behind the main lens), a camera modelled on the Illum;
//   - main lens: PRISM's, f 9.98445 mm at f/2 (the Illum's zoom at its wide end; Lytro
//     published a constant f/2.0);
//   - the raw: imageio's reader of Illum raw files (imageio, imageio/plugins/lytro.py) reads
//     5368 x 7728 pixels (LYTRO_ILLUM_IMAGE_SIZE) of 10 bits (four packed in five bytes); the
//     mosaic is GRBG (as Lytro's raws; the black level 64 and the noise figures are those of
//     scenes/realistic_raw.pov, not measured on an Illum).
// The lens is an ideal thin lens (a real Illum's 13-element zoom is not published).
//
// Declarations (a data-set spec sets them; defaults in brackets):
//   Twin_Focus          focus distance, m [2]
//   Dataset_Samples [16], Dataset_White_Image [1], Dataset_Sensor_Seed [1]
//   Dataset_Depth_Map [0]: also the depth map (the views export's disparity needs it)
// The white image, <stem>.white.png, is the camera's at its f/2, in DN (as the raw): Lytro ships
// one per zoom and focus setting, which a data-set spec sweeps (scenes/twin_lytro_illum.toml).
//
// Full size (41.5 Mpx; its time is a benchmark's, docs/digital-twins.md):
//   build/povray +Iscenes/twin_lytro_illum.pov +Lscenes +Otwin_illum.png +W7728 +H5368
// A crop around the sensor's centre:
//   build/povray +Iscenes/twin_lytro_illum.pov +Lscenes +Otwin_illum.png +W700 +H500
#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

#ifndef (Twin_Focus) #declare Twin_Focus = Scene_Focus; #end
#ifndef (Dataset_Samples) #declare Dataset_Samples = 16; #end
#ifndef (Dataset_White_Image) #declare Dataset_White_Image = 1; #end
#ifndef (Dataset_Sensor_Seed) #declare Dataset_Sensor_Seed = 1; #end
#ifndef (Dataset_Depth_Map) #declare Dataset_Depth_Map = 0; #end

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  mm_per_unit 1000
  main_lens {
    thin_lens
    focal_length 9.98445             // mm
    f_number 2
    focus_distance Twin_Focus
  }
  microlens_array {
    hexagonal
    pitch 0.020                      // mm
    focal_length 0.040087            // mm: f/2.0, matched to the main lens
    distance 0.040087                // d = f: plenoptic 1.0
  }
  sensor {
    pixel_size 0.0014                // mm
    bayer grbg                       // the Illum's mosaic
    bit_depth 10
    black_level 64
    full_well 4500
    exposure 3000
    read_noise 3
    seed Dataset_Sensor_Seed
  }
  samples Dataset_Samples
  #if (Dataset_White_Image) white_image #end
  #if (Dataset_Depth_Map) depth_map #end
}
