// SPDX-License-Identifier: AGPL-3.0-or-later
// Files beside the image, written atomically (see files.h).

#include "povray_glue/outputs/files.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <vector>

#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

namespace plenoptic {

namespace {

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
    // mkstemp creates the file for its owner only; the files beside the image get the permissions
    // the image gets (0666 less the umask), as any file the program writes.
    const mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, 0666 & ~mask);
    close(fd);
    return std::string(buffer.data());
}

void report_failure(const char* what, const std::string& path, int error)
{
    std::fprintf(stderr, "plenoptic camera: cannot write %s %s: %s\n", what, path.c_str(), std::strerror(error));
}

} // namespace

std::string replace_extension(const std::string& path, const std::string& suffix)
{
    const size_t slash = path.find_last_of('/');
    const size_t dot = path.find_last_of('.');
    const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
    return (has_ext ? path.substr(0, dot) : path) + suffix;
}

std::string base_name(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

namespace {

// Opens a temporary file beside `path`, lets write() fill it (false: failed), and renames it onto
// `path`; on failure reports and removes the temporary file.
bool write_through_temporary(const char* what, const std::string& path, const std::function<bool(FILE*)>& write)
{
    return write_file_streamed(what, path, [&](FILE* f) { return write(f) ? Fill::Complete : Fill::Failed; });
}

} // namespace

std::FILE* scratch_file_beside(const std::string& path)
{
    const std::string tmp = temporary_beside(path);
    if (tmp.empty())
        return nullptr;
    std::FILE* f = std::fopen(tmp.c_str(), "w+b");
    const int error = errno;
    std::remove(tmp.c_str());
    errno = error;
    return f;
}

bool write_file_streamed(const char* what, const std::string& path, const std::function<Fill(std::FILE* file)>& fill)
{
    const std::string tmp = temporary_beside(path);
    if (tmp.empty()) {
        report_failure(what, path, errno);
        return false;
    }
    FILE* f = std::fopen(tmp.c_str(), "wb");
    if (f == nullptr) {
        report_failure(what, path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    const Fill filled = fill(f);
    const bool closed = std::fclose(f) == 0;
    if (filled == Fill::Abandoned) {
        std::remove(tmp.c_str());
        return false;
    }
    if (!closed || filled != Fill::Complete || std::rename(tmp.c_str(), path.c_str()) != 0) {
        report_failure(what, path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    return true;
}

bool write_file_atomically(const char* what, const std::string& path, const std::string& bytes)
{
    return write_through_temporary(what, path, [&](FILE* f) {
        return std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    });
}

bool write_file_atomically(const char* what, const std::string& path,
                           const std::function<bool(std::string* piece)>& next)
{
    return write_through_temporary(what, path, [&](FILE* f) {
        std::string piece;
        while (next(&piece))
            if (std::fwrite(piece.data(), 1, piece.size(), f) != piece.size())
                return false;
        return true;
    });
}

bool write_float_exr(const std::string& path, const char* what, const char* channel, int W, int H,
                     const std::function<bool(int j, float* row)>& fill)
{
    const std::string tmp = temporary_beside(path);
    if (tmp.empty()) {
        report_failure(what, path, errno);
        return false;
    }
    bool complete = true;
    try {
        Imf::Header header(W, H);
        header.channels().insert(channel, Imf::Channel(Imf::FLOAT));
        Imf::OutputFile file(tmp.c_str(), header);
        std::vector<float> row(size_t(W), 0.0f);
        for (int j = 0; j < H && complete; ++j) {
            complete = fill(j, row.data());
            // The slice's base is where pixel (0, 0) would be, so that row j starts at `row`.
            Imf::FrameBuffer buffer;
            buffer.insert(channel, Imf::Slice(Imf::FLOAT, (char*)(row.data()) - sizeof(float) * size_t(W) * j,
                                              sizeof(float), sizeof(float) * W));
            file.setFrameBuffer(buffer);
            if (complete)
                file.writePixels(1);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "plenoptic camera: cannot write %s %s: %s\n", what, path.c_str(), e.what());
        std::remove(tmp.c_str());
        return false;
    }
    if (!complete) {
        std::remove(tmp.c_str());
        return false;
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        report_failure(what, path, errno);
        std::remove(tmp.c_str());
        return false;
    }
    return true;
}

} // namespace plenoptic
