// SPDX-License-Identifier: AGPL-3.0-or-later
// thin_lens_camera.pov: an ideal thin lens and a sensor, no microlens array: an ordinary
// camera with depth of field. A 50 mm f/1.8 lens focused at 2 m (on the marbled sphere) in
// front of a 36 mm x 27 mm sensor (45 um pixels at 800 x 600): the cube 1.35 m away and
// the brick wall 5 m away are visibly blurred, the sphere and the floor at 2 m are sharp.
//
// What the numbers give: D = 1 / (1/50 - 1/2000) = 51.28 mm (lens to sensor); field of
// view 2 atan(18 / 51.28) = 38.7 degrees; blur disc of a point at distance z:
// A D |1/2000 - 1/z| with A = 50/1.8 = 27.8 mm, i.e. 0.30 mm (6.6 px) for the cube and
// 0.43 mm (9.5 px) for the wall. The same picture comes from POV-Ray's own camera with
//   focal_blur: angle 38.7, focal_point 2 m ahead, aperture 2 A = 0.0556 (POV-Ray's
//   `aperture` is twice the lens diameter in scene units), blur_samples as below
// (tests/camera/test_thin_lens_vs_focal_blur.py compares the two).
//
// Render from the repository root:
//   build/povray +Iscenes/thin_lens_camera.pov +Lscenes +Othin_lens_camera.png +W800 +H600
// Beside the image: thin_lens_camera.plenoptic.json.

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  main_lens {
    thin_lens
    focal_length 50                  // F, mm
    f_number 1.8                     // aperture diameter A = F / 1.8 = 27.8 mm
    focus_distance Scene_Focus       // 2 m (scene units) in front of the lens
  }
  sensor { pixel_size 0.045 }        // 45 um: 800 x 600 pixels make a 36 x 27 mm sensor
  samples 16, 64                     // adaptive, as focal_blur: 16 rays, up to 64 where the
                                     // blur is noisy (confidence 0.9, variance 1/128)
}
