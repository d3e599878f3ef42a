// SPDX-License-Identifier: AGPL-3.0-or-later
// The white images' cache (see the header).

#include "povray_glue/outputs/white_image_cache.h"

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include <sys/stat.h>

#include <nlohmann/json.hpp>

#include "plenoptic/core/sampling.h"
#include "plenoptic/truth/metadata.h"
#include "povray_glue/outputs/files.h"

namespace plenoptic {

namespace {

// Two FNV-1a lanes of different starting values, each finished by SplitMix64's mixer: 128 bits.
// Not a cryptographic hash: entries are matched by their whole description, the key only names
// them.
struct Hash128 {
    std::uint64_t a = 0xcbf29ce484222325ULL, b = 0x84222325cbf29ce4ULL;
    void add(const char* bytes, size_t n)
    {
        for (size_t i = 0; i < n; ++i) {
            const std::uint64_t c = static_cast<unsigned char>(bytes[i]);
            a = (a ^ c) * 0x100000001b3ULL;
            b = (b ^ c) * 0x100000001b3ULL;
        }
    }
    std::string hex() const
    {
        char text[33];
        std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(mix64(a)),
                      static_cast<unsigned long long>(mix64(b ^ 0x9e3779b97f4a7c15ULL)));
        return text;
    }
};

std::string number(double v)
{
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return text;
}

bool read_file(const std::string& path, std::string* bytes)
{
    std::ifstream in(path.c_str(), std::ios::binary);
    if (!in)
        return false;
    std::ostringstream all;
    all << in.rdbuf();
    *bytes = all.str();
    return bool(in) || in.eof();
}

} // namespace

std::string white_image_description(const PlenopticCamera& optics, const CameraParams& params, double f_number, int index,
                                    bool raw, const std::string& executable)
{
    std::string text = "povray-plenoptic white image\nprogram " + executable + "\nf_number " + number(f_number) + "\nindex " +
                       std::to_string(index) + "\n" + (raw ? "raw (through the read-out)" : "linear") + "\n";
    // The lens table's rows (the metadata names the table's file, not its content).
    if (params.array.lens_table) {
        Hash128 rows;
        for (const LensTableRow& row : *params.array.lens_table) {
            const double values[] = {double(row.lens.k), double(row.lens.l), row.error.dx_mm, row.error.dy_mm, row.error.dz_mm,
                                     row.error.focal_factor, row.error.tilt_deg, row.error.tilt_azimuth_deg, row.focal_length_mm};
            rows.add(reinterpret_cast<const char*>(values), sizeof values);
        }
        text += "lens_table " + std::to_string(params.array.lens_table->size()) + " rows " + rows.hex() + "\n";
    }
    // Every resolved parameter of the camera, as the metadata writes it, seen from a fixed frame
    // (a white world looks the same from anywhere).
    text += "camera " + metadata_json(optics, params, CameraFrame{}, SidecarFiles()) + "\n";
    return text;
}

std::string white_image_key(const std::string& description)
{
    Hash128 hash;
    hash.add(description.data(), description.size());
    return hash.hex();
}

std::string executable_identity()
{
    std::string bytes;
    if (!read_file("/proc/self/exe", &bytes) || bytes.empty())
        return "";
    Hash128 hash;
    hash.add(bytes.data(), bytes.size());
    return hash.hex() + " (" + std::to_string(bytes.size()) + " bytes)";
}

WhiteImageCache WhiteImageCache::from_environment()
{
    WhiteImageCache cache;
    const char* folder = std::getenv(kWhiteImageCacheVariable);
    if (folder == nullptr || *folder == '\0')
        return cache;
    const std::string path(folder);
    if (mkdir(path.c_str(), 0777) != 0 && errno != EEXIST) {
        std::fprintf(stderr, "plenoptic camera: %s=%s: cannot make the folder (%s): white images are computed, not cached\n",
                     kWhiteImageCacheVariable, folder, std::strerror(errno));
        return cache;
    }
    struct stat status;
    if (stat(path.c_str(), &status) != 0 || !S_ISDIR(status.st_mode)) {
        std::fprintf(stderr, "plenoptic camera: %s=%s is not a folder: white images are computed, not cached\n",
                     kWhiteImageCacheVariable, folder);
        return cache;
    }
    cache.executable_ = executable_identity();
    if (cache.executable_.empty()) {
        std::fprintf(stderr, "plenoptic camera: %s: this program cannot read its own executable (/proc/self/exe), so a "
                             "cached white image could not be told from an older program's: white images are computed, "
                             "not cached\n", kWhiteImageCacheVariable);
        return cache;
    }
    cache.folder_ = path;
    return cache;
}

std::string WhiteImageCache::png_path(const std::string& description) const
{
    return folder_ + "/" + white_image_key(description) + ".png";
}

bool WhiteImageCache::find(const std::string& description, CachedWhiteImage* found) const
{
    if (!enabled())
        return false;
    const std::string stem = folder_ + "/" + white_image_key(description);
    std::string text, png;
    if (!read_file(stem + ".json", &text) || !read_file(stem + ".png", &png))
        return false;
    const nlohmann::json entry = nlohmann::json::parse(text, nullptr, false);
    if (entry.is_discarded() || !entry.is_object())
        return false;
    const auto d = entry.find("description"), s = entry.find("scale"), n = entry.find("png_bytes"), h = entry.find("png_hash");
    if (d == entry.end() || !d->is_string() || d->get<std::string>() != description)
        return false;
    if (s == entry.end() || !s->is_number() || n == entry.end() || !n->is_number_unsigned() || h == entry.end() || !h->is_string())
        return false;
    // The PNG is the one the entry was written with (not cut short, not another entry's).
    if (n->get<std::uint64_t>() != png.size() || h->get<std::string>() != white_image_key(png))
        return false;
    found->png = png;
    found->scale = s->get<double>();
    return true;
}

bool WhiteImageCache::store(const std::string& description, const CachedWhiteImage& entry) const
{
    if (!enabled())
        return false;
    const std::string stem = folder_ + "/" + white_image_key(description);
    nlohmann::json record = {{"description", description},
                             {"scale", entry.scale},
                             {"png_bytes", std::uint64_t(entry.png.size())},
                             {"png_hash", white_image_key(entry.png)}};
    // The PNG first: an entry is found only when its JSON is there and names this PNG.
    return write_file_atomically("cached white image", stem + ".png", entry.png) &&
           write_file_atomically("cached white image's record", stem + ".json", record.dump(1) + "\n");
}

} // namespace plenoptic
