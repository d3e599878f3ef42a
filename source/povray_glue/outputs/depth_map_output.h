// SPDX-License-Identifier: AGPL-3.0-or-later
// The depth map output (`depth_map`): <image>.depth.exr, the distance along each pixel's chief
// ray, from the lens it leaves to the first surface (+inf where it hits nothing, -1 where no
// sample of the pixel passes the apertures or the pixel was not rendered). Computed during the
// render, pixel by pixel on the thread that traces the pixel; a continued render (+C) computes
// the depth it owes for the blocks it does not trace again a share at a time with the traced
// pixels (DepthBackfill). The virtual depth output reads the map.

#ifndef POVRAY_GLUE_OUTPUTS_DEPTH_MAP_OUTPUT_H
#define POVRAY_GLUE_OUTPUTS_DEPTH_MAP_OUTPUT_H

#include "plenoptic/truth/depth_map.h"
#include "povray_glue/outputs/output.h"

namespace plenoptic {

class DepthMapOutput : public Output {
public:
    DepthMapOutput(const Render& render, const RenderArea& area);

    bool traces_pixels() const override { return true; }
    void pixel_traced(int column, int row, SceneProbe& scene) override;
    bool write(const WrittenImage& image, SidecarFiles& files) override;

    // The depth map of the image written, nullptr when the front end wrote another size than the
    // render's.
    const DepthMap* map_of(const WrittenImage& image) const;

private:
    float depth_of(int column, int row, SceneProbe& scene) const;

    const Render& render_;
    DepthMap map_;
    DepthBackfill backfill_;
};

} // namespace plenoptic

#endif
