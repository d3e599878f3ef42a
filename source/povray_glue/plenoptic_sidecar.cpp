// SPDX-License-Identifier: AGPL-3.0-or-later
// Metadata and depth-map files beside a plenoptic render (see plenoptic_sidecar.h).

#include "povray_glue/plenoptic_sidecar.h"

#include <cerrno>
#include <cmath>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <vector>

#include <stdlib.h>
#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

namespace plenoptic {

namespace {

struct Registration {
    std::shared_ptr<const CameraSetup> setup;
    RenderState state;
    int width = 0, height = 0;
    std::vector<float> depth;
};

std::mutex registration_mutex;
Registration registration;
// The registration as every pixel reads it, without the lock.
std::atomic<const CameraSetup*> registered_setup(nullptr);
std::atomic<long long> registered_size(0);  // W * 2^32 + H
std::atomic<const RenderState*> registered_state(nullptr);
std::atomic<int> next_depth_row(0);
std::atomic<int> depth_rows(0);

std::string replace_extension(const std::string& path, const std::string& suffix)
{
    const size_t slash = path.find_last_of('/');
    const size_t dot = path.find_last_of('.');
    const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
    return (has_ext ? path.substr(0, dot) : path) + suffix;
}

std::string directory_of(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string(".") : (slash == 0 ? std::string("/") : path.substr(0, slash));
}

// A new, empty file with a short name in the directory of `path` (so renaming it onto `path` is
// atomic, and a long output name does not become too long a temporary one); empty on failure.
std::string temporary_beside(const std::string& path)
{
    std::string name = directory_of(path) + "/.plenoptic-XXXXXX";
    std::vector<char> buffer(name.begin(), name.end());
    buffer.push_back('\0');
    const int fd = mkstemp(buffer.data());
    if (fd < 0)
        return "";
    close(fd);
    return std::string(buffer.data());
}

void report_failure(const char* what, const std::string& path, int error)
{
    std::fprintf(stderr, "plenoptic camera: cannot write %s %s: %s\n", what, path.c_str(), std::strerror(error));
}

bool write_text_atomically(const std::string& path, const std::string& text)
{
    const std::string tmp = temporary_beside(path);
    if (tmp.empty()) {
        report_failure("metadata", path, errno);
        return false;
    }
    FILE* f = std::fopen(tmp.c_str(), "wb");
    if (f == nullptr) {
        report_failure("metadata", path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !ok || std::rename(tmp.c_str(), path.c_str()) != 0) {
        report_failure("metadata", path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    return true;
}

bool write_depth_exr(const std::string& path, const std::vector<float>& depth, int W, int H)
{
    const std::string tmp = temporary_beside(path);
    if (tmp.empty()) {
        report_failure("depth map", path, errno);
        return false;
    }
    try {
        Imf::Header header(W, H);
        header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
        Imf::OutputFile file(tmp.c_str(), header);
        Imf::FrameBuffer buffer;
        buffer.insert("Z", Imf::Slice(Imf::FLOAT, (char*)depth.data(), sizeof(float), sizeof(float) * W));
        file.setFrameBuffer(buffer);
        file.writePixels(H);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "plenoptic camera: cannot write depth map %s: %s\n", path.c_str(), e.what());
        std::remove(tmp.c_str());
        return false;
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        report_failure("depth map", path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    return true;
}

// Called with registration_mutex held.
void forget_registration()
{
    registered_setup.store(nullptr);
    registered_state.store(nullptr);
    registered_size.store(0);
    depth_rows.store(0);
    registration = Registration();
}

std::string base_name(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

} // namespace

std::string metadata_path_for(const std::string& image_path) { return replace_extension(image_path, ".plenoptic.json"); }
std::string depth_path_for(const std::string& image_path) { return replace_extension(image_path, ".depth.exr"); }

namespace {

bool is_orthonormal(const CameraFrame& frame)
{
    const double* axes[3] = {frame.right, frame.up, frame.direction};
    for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) {
            const double dot = axes[a][0] * axes[b][0] + axes[a][1] * axes[b][1] + axes[a][2] * axes[b][2];
            if (std::fabs(dot - (a == b ? 1.0 : 0.0)) > 1e-12)
                return false;
        }
    return true;
}

} // namespace

const RenderState* sidecar_current(const CameraSetup* setup, int W, int H)
{
    const long long size = ((long long)W << 32) + H;
    if (registered_setup.load(std::memory_order_acquire) == setup &&
        registered_size.load(std::memory_order_acquire) == size)
        return registered_state.load(std::memory_order_acquire);
    return nullptr;
}

const RenderState* sidecar_register(const std::shared_ptr<const CameraSetup>& setup, const CameraFrame& frame, int W, int H)
{
    const long long size = ((long long)W << 32) + H;
    std::lock_guard<std::mutex> lock(registration_mutex);
    if (registered_setup.load() != setup.get() || registered_size.load() != size) {
        registered_setup.store(nullptr);
        registration.setup = setup;
        registration.width = W;
        registration.height = H;
        registration.depth.clear();
        // -1 marks a pixel that no light reaches (and one not rendered, e.g. outside +SR/+ER).
        if (setup->depth_map)
            registration.depth.assign(size_t(W) * size_t(H), -1.0f);
        registration.state.frame = frame;
        registration.state.frame_orthonormal = is_orthonormal(frame);
        registration.state.depth = registration.depth.empty() ? nullptr : registration.depth.data();
        registered_state.store(&registration.state);
        next_depth_row.store(0);
        depth_rows.store(registration.depth.empty() ? 0 : H);
        registered_size.store(size);
        registered_setup.store(setup.get(), std::memory_order_release);
    }
    return registered_state.load();
}

int sidecar_claim_depth_row()
{
    const int row = next_depth_row.fetch_add(1);
    return row < depth_rows.load() ? row : -1;
}

bool sidecar_write(const std::string& image_path, int W, int H)
{
    std::lock_guard<std::mutex> lock(registration_mutex);
    if (!registration.setup)
        return true;
    bool ok = true;
    // +O- : POV-Ray writes the image to standard output under the name "stdout"; there is no
    // file beside which the metadata could go.
    if (image_path == "stdout" || image_path == "stderr") {
        std::fprintf(stderr, "plenoptic camera: the image went to standard output (+O-), so no metadata or "
                             "depth map is written; give +O a file name to get them.\n");
        forget_registration();
        return true;
    }
    std::string depth_file;
    if (!registration.depth.empty() && W == registration.width && H == registration.height) {
        const std::string depth_path = depth_path_for(image_path);
        if (write_depth_exr(depth_path, registration.depth, W, H))
            depth_file = base_name(depth_path);
        else
            ok = false;
    }
    const std::string json = metadata_json(registration.setup->model, registration.setup->params, W, H,
                                           registration.state.frame, depth_file);
    const std::string metadata_path = metadata_path_for(image_path);
    if (!write_text_atomically(metadata_path, json))
        ok = false;
    forget_registration();
    return ok;
}

} // namespace plenoptic
