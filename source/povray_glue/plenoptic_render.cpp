// SPDX-License-Identifier: AGPL-3.0-or-later
// The start of a plenoptic render in POV-Ray (see plenoptic_render.h).

#include "povray_glue/plenoptic_render.h"

#include <algorithm>

#include "backend/frame.h"
#include "backend/control/messagefactory.h"
#include "backend/math/vector.h"
#include "backend/scene/camera.h"
#include "backend/scene/view.h"
#include "base/povmscpp.h"
#include "base/povmsgid.h"

#include "base/povdebug.h"

namespace pov {

unsigned int Plenoptic_Tracing_Method(ViewData& view, POVMS_Object& options, unsigned int method)
{
    const SceneData& scene = *view.GetSceneData();
    if (scene.parsedCamera.Type != PLENOPTIC_CAMERA)
        return method;
    if (options.TryGetBool(kPOVAttrib_Antialias, false))
        MessageFactory(10, 370, "Render", scene.backendAddress, scene.frontendAddress, scene.sceneId, view.GetViewId())
            .Warning(0, "plenoptic camera: antialiasing (+A) is ignored; the camera's own 'samples' sets how many rays "
                        "each pixel takes.");
    return 0;
}

std::shared_ptr<plenoptic::Render> Plenoptic_Start_Render(
    ViewData& view, unsigned int block_size, const std::vector<std::pair<unsigned int, unsigned int> >& finished_blocks)
{
    const Camera& camera = view.GetCamera();
    const POVRect& area = view.GetRenderArea();
    plenoptic::CameraFrame frame;
    Vector3d right(camera.Right), up(camera.Up), direction(camera.Direction);
    right.normalize();
    up.normalize();
    direction.normalize();
    // The optics frame's origin: the scene's location is a real lens's front vertex, the frame's
    // origin its rear vertex, the lens's length behind it.
    const double behind_units = camera.Plenoptic->model.lens_length_mm() / camera.Plenoptic->model.mm_per_unit;
    frame.location = plenoptic::Vec3{camera.Location[X] - behind_units * direction[X],
                                     camera.Location[Y] - behind_units * direction[Y],
                                     camera.Location[Z] - behind_units * direction[Z]};
    frame.right = plenoptic::Vec3{right[X], right[Y], right[Z]};
    frame.up = plenoptic::Vec3{up[X], up[Y], up[Z]};
    frame.direction = plenoptic::Vec3{direction[X], direction[Y], direction[Z]};
    // The blocks as POV-Ray's ViewData::GetNextRectangle cuts them from the render area.
    plenoptic::RenderArea traced;
    traced.area = plenoptic::PixelRect{int(area.left), int(area.top), int(area.right), int(area.bottom)};
    for (const std::pair<unsigned int, unsigned int>& block : finished_blocks) {
        const unsigned int left = area.left + block.first * block_size, top = area.top + block.second * block_size;
        if (left > area.right || top > area.bottom)
            continue;
        traced.untraced.push_back(plenoptic::PixelRect{int(left), int(top), int(std::min(left + block_size - 1, area.right)),
                                                       int(std::min(top + block_size - 1, area.bottom))});
    }
    std::shared_ptr<plenoptic::Render> render = std::make_shared<plenoptic::Render>(
        camera.Plenoptic, frame, int(view.GetWidth()), int(view.GetHeight()), traced);
    plenoptic::publish_render(int(view.GetViewId()), render);
    return render;
}

} // namespace pov
