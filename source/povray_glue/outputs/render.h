// SPDX-License-Identifier: AGPL-3.0-or-later
// One render of a plenoptic camera, as an explicit object: its camera setup, its camera with the
// render's film, its optics frame in the scene and the outputs it wants (output.h). Made once by
// View::StartRender (through Plenoptic_Start_Render, povray_glue/plenoptic_render.h) when the
// view's camera is final, carried to every render thread in the camera they copy, and handed to
// the front end, which writes the outputs beside the image, by the view that rendered it.

#ifndef POVRAY_GLUE_OUTPUTS_RENDER_H
#define POVRAY_GLUE_OUTPUTS_RENDER_H

#include <memory>
#include <vector>

#include "plenoptic/truth/metadata.h"
#include "povray_glue/outputs/output.h"
#include "povray_glue/plenoptic_setup.h"

namespace plenoptic {

class Render {
public:
    // `kinds`: the list the outputs come from (the tests give their own).
    Render(std::shared_ptr<const CameraSetup> setup, const CameraFrame& frame, int width, int height,
           const RenderArea& area, const std::vector<OutputKind>& kinds = output_kinds());
    ~Render();
    Render(const Render&) = delete;
    Render& operator=(const Render&) = delete;

    const CameraSetup& setup() const { return *setup_; }
    // The camera of this render: the parsed model with the render's film (width x height).
    const PlenopticCamera& model() const { return model_; }
    // The optics frame in the scene: +x right, +y up, +z towards the scene, unit axes.
    const CameraFrame& frame() const { return frame_; }
    // right, up, direction orthonormal: a unit optics direction stays unit in the scene.
    bool frame_orthonormal() const { return frame_orthonormal_; }
    int width() const { return model_.sensor.film.width; }
    int height() const { return model_.sensor.film.height; }
    // A continued render (+C): some of its pixels come from the image an earlier run wrote.
    bool continued() const { return continued_; }

    // The outputs this render wants, in the list's order, and their names.
    const std::vector<std::unique_ptr<Output> >& outputs() const { return outputs_; }
    std::vector<std::string> output_names() const;
    // This render's output of type T, or nullptr when it does not want it.
    template <class T>
    const T* output() const
    {
        for (const std::unique_ptr<Output>& o : outputs_)
            if (const T* found = dynamic_cast<const T*>(o.get()))
                return found;
        return nullptr;
    }

    // During the render, for pixel (column, row) on the thread that traces it: the outputs'
    // pixel_traced hooks. traces_pixels(): whether any output has one.
    bool traces_pixels() const { return !pixel_outputs_.empty(); }
    void pixel_traced(int column, int row, SceneProbe& scene) const
    {
        for (Output* o : pixel_outputs_)
            o->pixel_traced(column, row, scene);
    }

    // During the render, for pixel (column, row) on the thread that shades it: its white value, for
    // the output that keeps it (Output::keeps_white). keeps_white(): whether one does.
    bool keeps_white() const { return white_output_ != nullptr; }
    void pixel_white(int column, int row, double white) const { white_output_->pixel_white(column, row, white); }

private:
    std::shared_ptr<const CameraSetup> setup_;
    PlenopticCamera model_;
    CameraFrame frame_;
    bool frame_orthonormal_;
    bool continued_;
    std::vector<std::unique_ptr<Output> > outputs_;
    std::vector<const char*> names_;
    std::vector<Output*> pixel_outputs_;
    Output* white_output_ = nullptr;
};

// The hand-over to the front end, by the view that rendered (POV-Ray's view id: unique in the
// process). The render is held weakly: it lives as long as the view's camera holds it, so a view
// that never writes its image (cancelled, no output file) leaves nothing behind, and another
// view's render can never be taken for it. Publishing replaces the view's earlier render.
void publish_render(int view, const std::shared_ptr<Render>& render);
// The view's render without taking it (nullptr when there is none).
std::shared_ptr<Render> published_render(int view);
// The view's render, after which the view has none.
std::shared_ptr<Render> take_published_render(int view);

} // namespace plenoptic

#endif
