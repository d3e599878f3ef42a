// SPDX-License-Identifier: AGPL-3.0-or-later
// The outputs of a plenoptic render as a list of objects: the depth map, the virtual depth map,
// the microimage centres, the sensor's raw, the white images and the metadata, and diffraction,
// the stage that changes the picture before it is written. Each kind of output decides from the
// render (its camera setup) whether it is wanted and then writes itself; the render keeps the
// outputs it wants, in the list's order (output_list.cpp), and the drivers below run them.
//
// A new output is one file defining
//     std::unique_ptr<Output> start_<name>(const Render& render, const RenderArea& area);
// (nullptr: this render does not want it) and its line in the list (output_list.cpp).
//
// No POV-Ray types: the glue (source/povray_glue/) gives the picture, the scene and the stop
// request through the interfaces below, and the outputs are unit-tested on their own.

#ifndef POVRAY_GLUE_OUTPUTS_OUTPUT_H
#define POVRAY_GLUE_OUTPUTS_OUTPUT_H

#include <memory>
#include <string>
#include <vector>

#include "plenoptic/camera/plenoptic_camera.h"
#include "plenoptic/camera/rays.h"
#include "plenoptic/truth/depth_map.h"
#include "plenoptic/truth/metadata.h"

namespace plenoptic {

class Render;

// True once the user asked to stop (Ctrl-C); long work polls it.
typedef bool (*CancelQuery)();

// Where a render traces: its area (+SR/+ER), inclusive, and the blocks in it that a continued
// render (+C) does not trace again.
struct RenderArea {
    PixelRect area;
    std::vector<PixelRect> untraced;
};

// The picture the front end writes, in linear light (its working gamma undone), read by rows so
// that no output needs a copy of a large picture as a whole.
class Picture {
public:
    virtual ~Picture() {}
    virtual int width() const = 0;
    virtual int height() const = 0;
    // Rows first .. first + count - 1 (from the top), R, G, B interleaved: count W 3 values at `rgb`.
    virtual void read_rows(int first, int count, float* rgb) const = 0;
    // The whole picture the same way (small pictures: tests).
    std::vector<float> linear_rgb() const
    {
        std::vector<float> rgb(size_t(width()) * height() * 3);
        if (!rgb.empty())
            read_rows(0, height(), rgb.data());
        return rgb;
    }
};

// The picture before it is written, which a stage may change.
class EditablePicture : public Picture {
public:
    // Replaces R, G and B of rows first .. first + count - 1 (interleaved, linear, count W 3
    // values); the opacity stays.
    virtual void write_rows(int first, int count, const float* rgb) = 0;
};

// The scene as an output sees it during the render, on the thread that traces the pixel.
class SceneProbe {
public:
    virtual ~SceneProbe() {}
    // Distance in scene units along `ray` (optics frame) to the first surface; +inf: none.
    virtual double first_hit(const OpticsRay& ray) = 0;
    // Between two pieces of work: lets the render stop (Ctrl-C) or other work run.
    virtual void cooperate() = 0;
};

// The image the front end has just written, as the outputs after it see it.
struct WrittenImage {
    WrittenImage(const std::string& image_path, const Picture& image_picture, const PlenopticCamera& image_camera,
                 CancelQuery cancel)
        : path(image_path), picture(image_picture), camera(image_camera), cancelled(cancel) {}

    std::string path;        // dir/name.ext
    const Picture& picture;  // what was written (after the stages before it)
    PlenopticCamera camera;            // the render's camera with the film of the image written
    CancelQuery cancelled;

    // The file beside the image: dir/name<suffix>.
    std::string beside(const std::string& suffix) const;
};

// One output of one render. The hooks run in the list's order at three moments; each does
// nothing unless the output overrides it.
class Output {
public:
    virtual ~Output() {}

    // During the render: whether pixel_traced is wanted, and the hook itself, called for every
    // pixel traced (not during the pretrace), on the thread that traces it, before it is shaded.
    virtual bool traces_pixels() const { return false; }
    virtual void pixel_traced(int column, int row, SceneProbe& scene) { (void)column, (void)row, (void)scene; }
    // During the render: whether the output keeps each pixel's white value (what the pixel's own
    // samples give in a world of radiance 1: shade_pixel_and_white, camera/pixel.h), and the hook
    // that receives it, called once for every pixel shaded (not during the pretrace), on the thread
    // that shades it. At most one output of a render keeps it.
    virtual bool keeps_white() const { return false; }
    virtual void pixel_white(int column, int row, double white) { (void)column, (void)row, (void)white; }

    // Before the front end writes the image: may change the picture. false (with a message on
    // stderr): no image may be written; the later stages do not run.
    virtual bool prepare_picture(EditablePicture& picture, CancelQuery cancelled)
    {
        (void)picture, (void)cancelled;
        return true;
    }

    // After the image is written: writes this output's files (to a temporary name, renamed when
    // complete) and records in `files` what the metadata names. false (with a message on stderr):
    // a file could not be written. Every output's write runs, whatever an earlier one returned;
    // each looks at the stop request itself.
    virtual bool write(const WrittenImage& image, SidecarFiles& files)
    {
        (void)image, (void)files;
        return true;
    }
};

typedef std::unique_ptr<Output> (*StartOutput)(const Render& render, const RenderArea& area);

// An entry of the list: its name and what starts it for a render.
struct OutputKind {
    const char* name;
    StartOutput start;
};

// The list, in the order the outputs run.
const std::vector<OutputKind>& output_kinds();

// Before the image is written: every output's prepare_picture in order, stopping at the first
// that refuses (false).
bool prepare_picture(Render& render, EditablePicture& picture, CancelQuery cancelled);

// After the image `image_path` (showing `picture`) is written: every output's write in order.
// false when one of them failed.
bool write_outputs(Render& render, const std::string& image_path, const Picture& picture, CancelQuery cancelled);

} // namespace plenoptic

#endif
