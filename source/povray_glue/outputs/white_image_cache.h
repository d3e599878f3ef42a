// SPDX-License-Identifier: AGPL-3.0-or-later
// The white images' cache: a white image is a property of the camera alone (its optics, its
// sensor and read-out, the f-number it is computed at, its noise stream), not of the scene, so a
// data set of many scenes through one camera, its bands and its re-renders need it once. The
// cache is a folder the user names in the environment variable PLENOPTIC_WHITE_IMAGE_CACHE (no
// cache when it is unset or empty); each entry is the finished white-image PNG, <key>.png, and
// <key>.json with the entry's description and its linear scale.
//
// The key is a 128-bit hash of the description: the text of everything a white image depends on
// (the camera's metadata as it would be written with no scene, which holds every resolved optical
// and sensor parameter, the lens table's rows, the f-number, the white image's number (its noise
// frame), raw or linear, and the program itself, by a hash of its executable, so that a rebuilt
// program never reads an entry an older one wrote). An entry is used only when its stored
// description equals the wanted one byte for byte, so a hash collision cannot return another
// camera's image.

#ifndef POVRAY_GLUE_OUTPUTS_WHITE_IMAGE_CACHE_H
#define POVRAY_GLUE_OUTPUTS_WHITE_IMAGE_CACHE_H

#include <string>

#include "plenoptic/camera/plenoptic_camera.h"

namespace plenoptic {

// The environment variable naming the cache folder.
const char* const kWhiteImageCacheVariable = "PLENOPTIC_WHITE_IMAGE_CACHE";

// The text a white image's key is the hash of (see above). `executable` is the program's identity
// (executable_identity()); `index` the white image's number in its request, `raw` whether it
// goes through the read-out.
std::string white_image_description(const PlenopticCamera& optics, const CameraParams& params, double f_number, int index,
                                    bool raw, const std::string& executable);

// 32 hexadecimal digits: the key of a description.
std::string white_image_key(const std::string& description);

// A hash of this program's executable (/proc/self/exe), "" when it cannot be read (then nothing
// is cached: an entry could not be told from an older program's).
std::string executable_identity();

class WhiteImageCache {
public:
    // The folder PLENOPTIC_WHITE_IMAGE_CACHE names, created when missing; disabled (with a message
    // on stderr saying why) when the variable is unset or empty, the folder cannot be made, or the
    // program cannot be identified.
    static WhiteImageCache from_environment();
    // A cache in `folder` for a program of identity `executable` (tests).
    WhiteImageCache(const std::string& folder, const std::string& executable) : folder_(folder), executable_(executable) {}

    bool enabled() const { return !folder_.empty() && !executable_.empty(); }
    const std::string& folder() const { return folder_; }
    const std::string& executable() const { return executable_; }
    std::string png_path(const std::string& description) const;

    // Whether an entry of `description` is there (its PNG is checked only when copied out: a
    // damaged one is then not used, and the white image is computed).
    bool holds(const std::string& description) const;
    // Writes the entry of `description` to `path` (atomically, copied piece by piece) and its
    // scale (what the linear values were divided by, WhiteImageFile::scale) to *scale; false, and
    // `path` untouched, when there is none, or its description or files do not match (a damaged
    // or foreign entry is never used).
    bool copy_out(const std::string& description, const std::string& path, double* scale) const;
    // Stores the white image `png_path` as the entry of `description` (each file written
    // atomically: a reader never sees half an entry); false, with a message, when it cannot be
    // written (the render goes on).
    bool store(const std::string& description, const std::string& png_path, double scale) const;

private:
    WhiteImageCache() {}
    std::string folder_, executable_;
};

} // namespace plenoptic

#endif
