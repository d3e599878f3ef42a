// SPDX-License-Identifier: AGPL-3.0-or-later
// The run-time rule that finds the data and configuration directories from the executable's
// own directory (source/povray_glue/plenoptic_install_paths.h), on made-up directory trees.

#include "povray_glue/plenoptic_install_paths.h"

#include <set>
#include <string>

#include <gtest/gtest.h>

namespace {

std::set<std::string> g_dirs;  // the directories that "exist" in a test

bool fake_is_dir(const std::string& path)
{
    return g_dirs.count(path) != 0;
}

plenoptic::InstallDirs resolve(const std::string& exe_dir, std::set<std::string> dirs)
{
    g_dirs = dirs;
    return plenoptic::resolve_install_dirs(exe_dir, fake_is_dir);
}

} // namespace

TEST(InstallPaths, InstalledPrefixAnywhere)
{
    plenoptic::InstallDirs d = resolve("/opt/pp/bin", {"/opt/pp/share/povray-plenoptic/include"});
    EXPECT_EQ(d.data, "/opt/pp/share/povray-plenoptic");
    EXPECT_EQ(d.conf, "/opt/pp/etc/povray-plenoptic");
}

TEST(InstallPaths, UsrKeepsItsConfigurationInEtc)
{
    plenoptic::InstallDirs d = resolve("/usr/bin", {"/usr/share/povray-plenoptic/include"});
    EXPECT_EQ(d.data, "/usr/share/povray-plenoptic");
    EXPECT_EQ(d.conf, "/etc/povray-plenoptic");
    d = resolve("/usr/local/bin", {"/usr/local/share/povray-plenoptic/include"});
    EXPECT_EQ(d.conf, "/usr/local/etc/povray-plenoptic");
}

TEST(InstallPaths, BuildTree)
{
    plenoptic::InstallDirs d = resolve("/src/build", {"/src/build/share/povray-3.7/include"});
    EXPECT_EQ(d.data, "/src/build/share/povray-3.7");
    EXPECT_EQ(d.conf, "/src/build/etc/povray/3.7");
}

TEST(InstallPaths, InstalledLayoutWinsOverABuildTreeBesideIt)
{
    plenoptic::InstallDirs d = resolve("/p/bin", {"/p/share/povray-plenoptic/include",
                                                  "/p/bin/share/povray-3.7/include"});
    EXPECT_EQ(d.data, "/p/share/povray-plenoptic");
}

TEST(InstallPaths, NothingFoundFallsBackToThePackagesDirectories)
{
    for (const char* exe_dir : {"/home/u/bin", "/", "", "relative/bin"}) {
        plenoptic::InstallDirs d = resolve(exe_dir, {});
        EXPECT_EQ(d.data, "/usr/share/povray-plenoptic") << exe_dir;
        EXPECT_EQ(d.conf, "/etc/povray-plenoptic") << exe_dir;
    }
    // A share tree without include/ is not an installation.
    plenoptic::InstallDirs d = resolve("/q/bin", {"/q/share/povray-plenoptic"});
    EXPECT_EQ(d.data, "/usr/share/povray-plenoptic");
}

TEST(InstallPaths, UserDirectoryIsTheForksOwn)
{
    EXPECT_EQ(plenoptic::pov_user_dir("/home/u"), "/home/u/.povray-plenoptic/3.7");
    EXPECT_EQ(plenoptic::pov_user_dir(""), "");
}
