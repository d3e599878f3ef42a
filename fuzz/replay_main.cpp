// SPDX-License-Identifier: AGPL-3.0-or-later
// Replays fuzz inputs through LLVMFuzzerTestOneInput without libFuzzer: any compiler, any build.
//   plenoptic_fuzz_replay fuzz/corpus [more files or directories]
// Each input runs in a child process, so that one that breaks an invariant (abort) does not hide
// the others; exits non-zero when any input failed, naming each.

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <dirent.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

bool is_directory(const std::string& path)
{
    struct stat st;
    return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

void collect(const std::string& path, std::vector<std::string>* files)
{
    if (!is_directory(path)) {
        files->push_back(path);
        return;
    }
    DIR* dir = opendir(path.c_str());
    if (dir == nullptr)
        return;
    while (dirent* entry = readdir(dir)) {
        const std::string name = entry->d_name;
        if (name != "." && name != "..")
            collect(path + "/" + name, files);
    }
    closedir(dir);
}

} // namespace

int main(int argc, char** argv)
{
    std::vector<std::string> files;
    for (int a = 1; a < argc; ++a)
        collect(argv[a], &files);
    if (files.empty()) {
        std::fprintf(stderr, "usage: %s corpus-dir-or-file...\n(no input found)\n", argv[0]);
        return 2;
    }
    int passed = 0, failed = 0;
    for (const std::string& file : files) {
        std::ifstream in(file, std::ios::binary);
        if (!in) {
            std::fprintf(stderr, "cannot read %s\n", file.c_str());
            return 2;
        }
        const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        std::fflush(stdout);
        std::fflush(stderr);
        const pid_t child = fork();
        if (child == 0) {
            LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
            std::fflush(stderr);
            _exit(0);
        }
        int status = 0;
        if (child < 0 || waitpid(child, &status, 0) != child) {
            std::fprintf(stderr, "cannot run %s\n", file.c_str());
            return 2;
        }
        if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
            ++passed;
        } else {
            ++failed;
            std::printf("FAIL %s (%s %d)\n", file.c_str(), WIFSIGNALED(status) ? "signal" : "exit",
                        WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status));
        }
    }
    std::printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
