// SPDX-License-Identifier: AGPL-3.0-or-later
// camera_array.pov: a bare pinhole array, no main lens: a rig of 9 x 7 pinhole cameras
// side by side (like the Stanford multi-camera array), each imaging onto its own patch of
// one shared sensor. Each 80 x 80 pixel tile is a complete little perspective view taken
// from its own pinhole, 80 mm from its neighbours: the near cube shifts by about 6.5 pixels
// from tile to tile, the sphere by 4.4, the brick wall by under 2 (disparity = pitch x d /
// (distance x pixel size) = 80 x 110 / (z x 1) pixels with z in mm).
//
// Geometry: the pinholes sit on a rectangular grid of pitch 80 mm centred on the camera's
// location; the sensor is d = 110 mm behind them with 1 mm pixels (a virtual sensor as
// large as the rig: a pixel belongs to the pinhole straight above it, so each pinhole's
// view is the 80 x 80 mm patch below it). Each view covers 2 atan(40 / 110) = 40 degrees.
// With an odd number of tiles across (+W720 = 9 tiles, +H560 = 7 tiles) the centre tile
// is the view from the camera's location itself and every tile is whole.
//
// Render from the repository root:
//   build/povray +Iscenes/camera_array.pov +Lscenes +Ocamera_array.png +W720 +H560
// Beside the image: camera_array.plenoptic.json, whose microimage_lattice gives every
// tile's centre in pixels (here exactly the pinholes' positions: origin (359.5, 279.5),
// basis (-80, 0) and (0, 80): +x in the camera is towards the left of the image).

#version 3.7;
global_settings { assumed_gamma 1.0 }
#include "plenoptic_scene.inc"

camera {
  plenoptic
  location Scene_Location            // the centre of the array (there is no main lens)
  look_at  Scene_Look_At
  microlens_array {
    rectangular
    pitch 80                         // mm between neighbouring pinholes
    pinhole
    distance 110                     // d: pinholes -> sensor, mm
  }
  sensor { pixel_size 1 }            // mm
  samples 4                          // average over each pixel's area (antialiasing)
}
