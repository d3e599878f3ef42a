// SPDX-License-Identifier: AGPL-3.0-or-later
// pinhole_camera.pov: the plenoptic camera reduced to a pinhole (main_lens pinhole, no
// microlens array). It is POV-Ray's perspective camera described by a physical sensor:
// a pinhole D = 8 mm in front of a sensor of 10 um pixels. At 640 x 480 the sensor is
// 6.4 mm x 4.8 mm, so the horizontal field of view is 2 atan(6.4 / (2 * 8)) = 43.6 degrees,
// and this image is pixel for pixel the one of
//   camera { perspective location Scene_Location look_at Scene_Look_At
//            right x*640/480 up y angle 43.6028 }
// (tests/camera/test_pinhole_vs_perspective.py checks exactly that). Everything is sharp:
// a pinhole has no depth of field. Use it as the all-in-focus reference of the other scenes.
//
// Render from the repository root:
//   build/povray +Iscenes/pinhole_camera.pov +Lscenes +Opinhole_camera.png +W640 +H480
// The pixel count is the sensor's: more pixels widen the view, they do not refine it.
// Beside the image: pinhole_camera.plenoptic.json (docs/metadata.md).

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location
  look_at  Scene_Look_At
  main_lens { pinhole distance 8 }   // D = 8 mm: the pinhole's distance to the sensor
  sensor { pixel_size 0.01 }         // 10 um square pixels
  // one ray per pixel (the default): the pixel centre through the pinhole, as the stock
  // camera without antialiasing; use e.g. samples 4 to average over the pixel area
}
