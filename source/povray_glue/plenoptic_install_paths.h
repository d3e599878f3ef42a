// SPDX-License-Identifier: AGPL-3.0-or-later
// Where the program finds POV-Ray's include files and its povray.ini/povray.conf: derived at run
// time from the executable's own location (/proc/self/exe), so an installed prefix can be moved
// and the build tree works as is. Replaces upstream's compiled-in POVLIBDIR/POVCONFDIR
// (patch 0007 calls these functions from vfe/unix/). See docs/install.md.
//
//   <prefix>/bin/povray-plenoptic  ->  data   <prefix>/share/povray-plenoptic
//                                      config <prefix>/etc/povray-plenoptic
//                                             (/etc/povray-plenoptic when <prefix> is /usr)
//   <build>/povray                 ->  data   <build>/share/povray-3.7
//                                      config <build>/etc/povray/3.7
//   neither found                  ->  /usr/share/povray-plenoptic, /etc/povray-plenoptic

#ifndef POVRAY_GLUE_PLENOPTIC_INSTALL_PATHS_H
#define POVRAY_GLUE_PLENOPTIC_INSTALL_PATHS_H

#include <string>
#include <vector>

namespace plenoptic {

struct InstallDirs {
    std::string data;  // include/, ini/, scenes/, docs/ (POV-Ray's %INSTALLDIR%)
    std::string conf;  // povray.ini, povray.conf
};

// The rule above for an executable in directory exe_dir (absolute, symlinks resolved);
// is_dir tells whether a directory exists (a parameter so the rule can be tested alone).
InstallDirs resolve_install_dirs(const std::string& exe_dir, bool (*is_dir)(const std::string&));

// The running program's directories (resolved once; the strings live as long as the program).
const std::string& pov_data_dir();
const std::string& pov_conf_dir();

// Library paths always added after povray.ini's and the command line's (lowest priority):
// the data directory, its ini/ and its include/, as Debian's povray.ini lists them.
const std::vector<std::string>& pov_library_paths();

// The user's own povray.ini/povray.conf: <home>/.povray-plenoptic/3.7 (Debian's povray reads
// <home>/.povray/3.7; the two programs do not share settings). Empty without a home.
std::string pov_user_dir(const std::string& home);

} // namespace plenoptic

#endif
