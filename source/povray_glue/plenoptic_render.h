// SPDX-License-Identifier: AGPL-3.0-or-later
// The start of a plenoptic render in POV-Ray: View::StartRender turns supersampling off for the
// plenoptic camera (patch 0006) and makes the render's state (outputs/render.h, patch 0008) once
// the view's camera is final, before any render task copies the camera, and hands it over to the
// front end under the view's id (publish_render).

#ifndef POVRAY_GLUE_PLENOPTIC_RENDER_H
#define POVRAY_GLUE_PLENOPTIC_RENDER_H

#include <memory>
#include <utility>
#include <vector>

#include "povray_glue/outputs/render.h"

class POVMS_Object;

namespace pov {

class ViewData;

// How View::StartRender traces the view's pixels: `method` as it chose it (0: one ray a pixel; 1,
// 2: supersampling, +A), unless the view's camera is plenoptic. That camera integrates each pixel
// itself with its own `samples`, and supersampling would mix in the neighbours: 0, with a warning
// when +A asked for more.
unsigned int Plenoptic_Tracing_Method(ViewData& view, POVMS_Object& options, unsigned int method);

// Called by View::StartRender once the view's camera is final and before any render task copies
// it: makes the render's state of the view (its camera, size, render area and id) and publishes
// it. finished_blocks: (column, row) of the render blocks a continued render (+C) will not trace,
// blocks of block_size pixels from the area's top-left corner.
std::shared_ptr<plenoptic::Render> Plenoptic_Start_Render(
    ViewData& view, unsigned int block_size, const std::vector<std::pair<unsigned int, unsigned int> >& finished_blocks);

} // namespace pov

#endif
