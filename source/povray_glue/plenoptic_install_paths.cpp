// SPDX-License-Identifier: AGPL-3.0-or-later
// Run-time data and configuration directories (see plenoptic_install_paths.h).

#include "povray_glue/plenoptic_install_paths.h"

#include <climits>
#include <cstdlib>
#include <sys/stat.h>

namespace plenoptic {

namespace {

const char kInstalledData[] = "/share/povray-plenoptic";
const char kInstalledConf[] = "/etc/povray-plenoptic";
const char kBuildTreeData[] = "/share/povray-3.7";
const char kBuildTreeConf[] = "/etc/povray/3.7";

bool directory_exists(const std::string& path)
{
    struct stat st;
    return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string parent_of(const std::string& dir)
{
    std::string::size_type slash = dir.find_last_of('/');
    if(slash == std::string::npos || slash == 0)
        return "";  // "/" or not absolute: no parent prefix
    return dir.substr(0, slash);
}

std::string executable_dir()
{
    char resolved[PATH_MAX];
    if(realpath("/proc/self/exe", resolved) == nullptr)
        return "";
    std::string exe(resolved);
    std::string::size_type slash = exe.find_last_of('/');
    return slash == std::string::npos ? std::string() : exe.substr(0, slash);
}

const InstallDirs& running_dirs()
{
    static const InstallDirs dirs = resolve_install_dirs(executable_dir(), directory_exists);
    return dirs;
}

} // namespace

InstallDirs resolve_install_dirs(const std::string& exe_dir, bool (*is_dir)(const std::string&))
{
    InstallDirs dirs;
    if(!exe_dir.empty() && exe_dir[0] == '/')
    {
        // Installed: <prefix>/bin/povray-plenoptic. The GNU convention puts /usr's configuration
        // in /etc (as CMake's GNUInstallDirs and platform/install.cmake do).
        std::string prefix = parent_of(exe_dir);
        if(!prefix.empty() && is_dir(prefix + kInstalledData + "/include"))
        {
            dirs.data = prefix + kInstalledData;
            dirs.conf = (prefix == "/usr" ? std::string() : prefix) + kInstalledConf;
            return dirs;
        }
        // The build tree: <build>/povray with <build>/share and <build>/etc staged by CMake.
        if(is_dir(exe_dir + kBuildTreeData + "/include"))
        {
            dirs.data = exe_dir + kBuildTreeData;
            dirs.conf = exe_dir + kBuildTreeConf;
            return dirs;
        }
    }
    // Neither (no /proc, or the binary copied away alone): the Debian package's directories.
    dirs.data = std::string("/usr") + kInstalledData;
    dirs.conf = kInstalledConf;
    return dirs;
}

const std::string& pov_data_dir()
{
    return running_dirs().data;
}

const std::string& pov_conf_dir()
{
    return running_dirs().conf;
}

const std::vector<std::string>& pov_library_paths()
{
    static const std::vector<std::string> paths{ pov_data_dir(), pov_data_dir() + "/ini",
                                                 pov_data_dir() + "/include" };
    return paths;
}

std::string pov_user_dir(const std::string& home)
{
    if(home.empty())
        return "";
    return home + "/.povray-plenoptic/3.7";
}

} // namespace plenoptic
