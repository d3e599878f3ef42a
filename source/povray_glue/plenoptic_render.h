// SPDX-License-Identifier: AGPL-3.0-or-later
// One render of a plenoptic camera, as an explicit object: made once by View::StartRender (patch
// 0008) when the view's camera is final, carried to every render thread in the camera they copy,
// and published for the front end, which writes the metadata and depth map beside the image.

#ifndef POVRAY_GLUE_PLENOPTIC_RENDER_H
#define POVRAY_GLUE_PLENOPTIC_RENDER_H

#include <memory>
#include <utility>
#include <vector>

#include "plenoptic/truth/depth_map.h"
#include "plenoptic/truth/metadata.h"
#include "povray_glue/plenoptic_setup.h"

namespace plenoptic {

class Render {
public:
    // area: the pixels this render covers (+SR/+ER), inclusive; untraced: the blocks in it that
    // a continued render (+C) does not trace again (their depth is still owed).
    Render(std::shared_ptr<const CameraSetup> setup, const CameraFrame& frame, int width, int height,
           PixelRect area, const std::vector<PixelRect>& untraced);

    const CameraSetup& setup() const { return *setup_; }
    // The camera of this render: the parsed model with the render's film (width x height).
    const Model& model() const { return model_; }
    // The optics frame in the scene: +x right, +y up, +z towards the scene, unit axes.
    const CameraFrame& frame() const { return frame_; }
    // right, up, direction orthonormal: a unit optics direction stays unit in the scene.
    bool frame_orthonormal() const { return frame_orthonormal_; }
    int width() const { return width_; }
    int height() const { return height_; }
    // nullptr unless the camera asked for a depth map.
    DepthMap* depth() { return depth_.get(); }
    const DepthMap* depth() const { return depth_.get(); }
    DepthBackfill* backfill() { return backfill_.get(); }
    const DepthBackfill* backfill() const { return backfill_.get(); }
    // A continued render (+C): some of its pixels come from the image an earlier run wrote.
    bool continued() const { return continued_; }

private:
    std::shared_ptr<const CameraSetup> setup_;
    Model model_;
    CameraFrame frame_;
    bool frame_orthonormal_;
    int width_, height_;
    bool continued_;
    std::unique_ptr<DepthMap> depth_;
    std::unique_ptr<DepthBackfill> backfill_;
};

// The render whose image the front end writes next. Publishing replaces any earlier one (an
// animation's next frame, a render that was cancelled); taking empties the slot.
void publish_render(std::shared_ptr<Render> render);
std::shared_ptr<Render> take_published_render();
// The published render without taking it (nullptr when there is none).
std::shared_ptr<Render> published_render();

} // namespace plenoptic

namespace pov_base { struct POVRect; }

namespace pov {

class Camera;

// Called by View::StartRender once the view's camera is final and before any render task copies
// it: makes the render's state and publishes it. finished_blocks: (column, row) of the render
// blocks a continued render (+C) will not trace, blocks of block_size pixels from the area's
// top-left corner.
std::shared_ptr<plenoptic::Render> Plenoptic_Start_Render(
    const Camera& camera, unsigned int width, unsigned int height, const pov_base::POVRect& area, unsigned int block_size,
    const std::vector<std::pair<unsigned int, unsigned int> >& finished_blocks);

} // namespace pov

#endif
