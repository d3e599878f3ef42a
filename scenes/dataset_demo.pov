// SPDX-License-Identifier: AGPL-3.0-or-later
// A scene for plenoptic-dataset (docs/datasets.md): a plenoptic 1.0 camera looks at a textured
// sphere in front of a wall. The data set's spec sweeps or draws the identifiers declared with
// defaults below (Declare= overrides them) and passes its per-item options as Dataset_*.
//   plenoptic-dataset run scenes/dataset_demo.toml --out /tmp/demo-dataset
#version 3.7;
global_settings { assumed_gamma 1.0 }

#ifndef (Sphere_X) #declare Sphere_X = 0; #end
#ifndef (Sphere_Z) #declare Sphere_Z = 1.2; #end
#ifndef (Sphere_Radius) #declare Sphere_Radius = 0.015; #end
#ifndef (Wall_Z) #declare Wall_Z = 2.5; #end
#ifndef (Focus) #declare Focus = 1.5; #end
#ifndef (Dataset_Samples) #declare Dataset_Samples = 8; #end
#ifndef (Dataset_Depth_Map) #declare Dataset_Depth_Map = 1; #end
#ifndef (Dataset_White_Image) #declare Dataset_White_Image = 0; #end

camera {
  plenoptic
  location <0, 0, 0> look_at <0, 0, 1>
  main_lens { thin_lens focal_length 50 f_number 2.5 focus_distance Focus }
  microlens_array { hexagonal pitch 0.1 focal_length 0.25 distance 0.25 }
  sensor { pixel_size 0.01 }
  samples Dataset_Samples
  depth_map (Dataset_Depth_Map)
  #if (Dataset_White_Image) white_image #end
}
#declare Glow = finish { emission 1 diffuse 0 ambient 0 }
sphere { <Sphere_X, 0, Sphere_Z>, Sphere_Radius
  pigment { checker rgb <0.9, 0.3, 0.2> rgb <0.2, 0.4, 0.9> scale 0.004 } finish { Glow } }
plane { z, Wall_Z pigment { bozo color_map { [0 rgb 0.2] [1 rgb 0.9] } scale 0.01 } finish { Glow } }
