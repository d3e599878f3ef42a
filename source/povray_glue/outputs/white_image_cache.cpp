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
#include <vector>

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

// Copies what is left of `in` to `out`, a megabyte at a time, hashing it and counting its bytes;
// false when a read or a write fails.
bool copy_file(std::FILE* in, std::FILE* out, Hash128* hash, std::uint64_t* bytes)
{
    std::vector<char> buffer(1 << 20);
    for (;;) {
        const size_t n = std::fread(buffer.data(), 1, buffer.size(), in);
        if (n > 0) {
            hash->add(buffer.data(), n);
            *bytes += n;
            if (std::fwrite(buffer.data(), 1, n, out) != n)
                return false;
        }
        if (n < buffer.size())
            return !std::ferror(in);
    }
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
    std::FILE* exe = std::fopen("/proc/self/exe", "rb");
    if (exe == nullptr)
        return "";
    Hash128 hash;
    std::uint64_t bytes = 0;
    std::vector<char> buffer(1 << 20);
    size_t n;
    while ((n = std::fread(buffer.data(), 1, buffer.size(), exe)) > 0) {
        hash.add(buffer.data(), n);
        bytes += n;
    }
    const bool read = !std::ferror(exe);
    std::fclose(exe);
    if (!read || bytes == 0)
        return "";
    return hash.hex() + " (" + std::to_string(bytes) + " bytes)";
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

namespace {

// The entry of `description` in `folder` (its JSON, with the fields copy_out reads) into *entry;
// false when there is none or it is not this description's.
bool read_entry(const std::string& folder, const std::string& description, nlohmann::json* entry)
{
    std::string text;
    if (!read_file(folder + "/" + white_image_key(description) + ".json", &text))
        return false;
    *entry = nlohmann::json::parse(text, nullptr, false);
    if (entry->is_discarded() || !entry->is_object())
        return false;
    const auto d = entry->find("description"), s = entry->find("scale"), n = entry->find("png_bytes"),
               h = entry->find("png_hash");
    if (d == entry->end() || !d->is_string() || d->get<std::string>() != description)
        return false;
    return s != entry->end() && s->is_number() && n != entry->end() && n->is_number_unsigned() && h != entry->end() &&
           h->is_string();
}

} // namespace

bool WhiteImageCache::holds(const std::string& description) const
{
    nlohmann::json entry;
    return enabled() && read_entry(folder_, description, &entry);
}

bool WhiteImageCache::copy_out(const std::string& description, const std::string& path, double* scale) const
{
    if (!enabled())
        return false;
    const std::string stem = folder_ + "/" + white_image_key(description);
    nlohmann::json entry;
    if (!read_entry(folder_, description, &entry))
        return false;
    const auto s = entry.find("scale"), n = entry.find("png_bytes"), h = entry.find("png_hash");
    std::FILE* in = std::fopen((stem + ".png").c_str(), "rb");
    if (in == nullptr)
        return false;
    // The PNG is the one the entry was written with (not cut short, not another entry's): checked
    // as it is copied, and the copy abandoned when it is not.
    const bool copied = write_file_streamed("white image", path, [&](std::FILE* out) -> Fill {
        Hash128 hash;
        std::uint64_t bytes = 0;
        if (!copy_file(in, out, &hash, &bytes))
            return std::ferror(out) ? Fill::Failed : Fill::Abandoned;
        return bytes == n->get<std::uint64_t>() && hash.hex() == h->get<std::string>() ? Fill::Complete : Fill::Abandoned;
    });
    std::fclose(in);
    if (copied)
        *scale = s->get<double>();
    return copied;
}

bool WhiteImageCache::store(const std::string& description, const std::string& png_path, double scale) const
{
    if (!enabled())
        return false;
    const std::string stem = folder_ + "/" + white_image_key(description);
    std::FILE* in = std::fopen(png_path.c_str(), "rb");
    if (in == nullptr) {
        std::fprintf(stderr, "plenoptic camera: cannot read %s to cache it: %s\n", png_path.c_str(), std::strerror(errno));
        return false;
    }
    Hash128 hash;
    std::uint64_t bytes = 0;
    // The PNG first: an entry is found only when its JSON is there and names this PNG.
    const bool copied = write_file_streamed("cached white image", stem + ".png", [&](std::FILE* out) {
        return copy_file(in, out, &hash, &bytes) ? Fill::Complete : Fill::Failed;
    });
    std::fclose(in);
    if (!copied)
        return false;
    const nlohmann::json record = {
        {"description", description}, {"scale", scale}, {"png_bytes", bytes}, {"png_hash", hash.hex()}};
    return write_file_atomically("cached white image's record", stem + ".json", record.dump(1) + "\n");
}

} // namespace plenoptic
