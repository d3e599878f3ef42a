# SPDX-License-Identifier: AGPL-3.0-or-later
# The installed program (included by CMakeLists.txt): what `cmake --install build --prefix P`
# puts under P, and the Debian package tools/package builds from the same install. Every name
# differs from Debian's povray and povray-includes, so both install side by side. The binary
# finds its data and configuration relative to itself at run time
# (source/povray_glue/plenoptic_install_paths.cpp), so P can be moved. See docs/install.md.
#
#   P/bin/povray-plenoptic                       the renderer (build/povray in the build tree)
#   P/bin/plenoptic-project                      forward projection (source/tools/)
#   P/bin/plenoptic-decode                       the decoder's launcher (source/tools/python_tools.cmake)
#   P/bin/plenoptic-targets                      calibration targets with ground truth (the same)
#   P/bin/plenoptic-dataset                      data sets, here or on Slurm (the same)
#   P/bin/plenoptic-lens                         lens import, info and drawing (the same)
#   P/bin/plenoptic-export                       a render in other tools' formats (the same)
#   P/bin/plenoptic-lens-data                    a lens file's optics as JSON, for plenoptic-lens (source/tools/)
#   P/lib/python3/dist-packages/plenoptic_lf/    the Python tools' package (python/plenoptic_lf/)
#   P/share/povray-plenoptic/include/, ini/      POV-Ray's own include and ini files
#   P/share/povray-plenoptic/scenes/             the repository's scenes/
#   P/share/povray-plenoptic/lenses/             the repository's lenses/ (main-lens prescriptions)
#   P/share/povray-plenoptic/docs/               docs/*.md, docs/metadata.schema.json, README.md, LICENSE
#   P/share/man/man1/*.1                         povray-plenoptic, plenoptic-project, plenoptic-decode, plenoptic-targets,
#                                                plenoptic-dataset, plenoptic-lens, plenoptic-export
#   P/share/doc/povray-plenoptic/copyright       the licence (Debian's place for it)
#   P/etc/povray-plenoptic/povray.ini, .conf     /etc/povray-plenoptic when P is /usr (GNU rule)

set(PLENOPTIC_DATA_DEST share/povray-plenoptic)

# The renderer under its own name (the build tree keeps build/povray). install(PROGRAMS) has no
# --strip of its own, so strip here when asked (cmake --install --strip, CPACK_STRIP_FILES).
install(PROGRAMS "$<TARGET_FILE:povray>" DESTINATION bin RENAME povray-plenoptic)
if(CMAKE_STRIP)
  install(CODE "if(CMAKE_INSTALL_DO_STRIP)
  execute_process(COMMAND \"${CMAKE_STRIP}\" \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/bin/povray-plenoptic\")
endif()")
endif()

# Data: POV-Ray's include/ and ini/ (from the fetched source, as staged in the build tree),
# our scenes, lens prescriptions and documentation.
install(DIRECTORY "${_upstream}/distribution/include" "${_upstream}/distribution/ini"
        DESTINATION "${PLENOPTIC_DATA_DEST}")
install(DIRECTORY "${CMAKE_SOURCE_DIR}/scenes/" DESTINATION "${PLENOPTIC_DATA_DEST}/scenes")
install(DIRECTORY "${CMAKE_SOURCE_DIR}/lenses/" DESTINATION "${PLENOPTIC_DATA_DEST}/lenses")
install(DIRECTORY "${CMAKE_SOURCE_DIR}/docs/" DESTINATION "${PLENOPTIC_DATA_DEST}/docs"
        FILES_MATCHING PATTERN "*.md" PATTERN "*.schema.json")
install(FILES "${CMAKE_SOURCE_DIR}/README.md" "${CMAKE_SOURCE_DIR}/LICENSE"
        DESTINATION "${PLENOPTIC_DATA_DEST}/docs")
install(FILES "${CMAKE_SOURCE_DIR}/LICENSE" DESTINATION share/doc/povray-plenoptic RENAME copyright)
install(FILES "${CMAKE_SOURCE_DIR}/platform/man/povray-plenoptic.1"
              "${CMAKE_SOURCE_DIR}/platform/man/plenoptic-project.1"
              "${CMAKE_SOURCE_DIR}/platform/man/plenoptic-decode.1"
              "${CMAKE_SOURCE_DIR}/platform/man/plenoptic-targets.1"
              "${CMAKE_SOURCE_DIR}/platform/man/plenoptic-dataset.1"
              "${CMAKE_SOURCE_DIR}/platform/man/plenoptic-lens.1"
              "${CMAKE_SOURCE_DIR}/platform/man/plenoptic-export.1"
        DESTINATION share/man/man1)

# Configuration: the build tree's povray.ini and povray.conf (no path in them names a prefix).
# <prefix>/etc/povray-plenoptic, except /etc/povray-plenoptic for the prefix /usr: the rule
# plenoptic_install_paths.cpp applies at run time. Decided at install time, since
# `cmake --install --prefix` chooses the prefix then.
install(CODE "string(REGEX REPLACE \"(.)/+\$\" \"\\\\1\" _plenoptic_prefix \"\${CMAKE_INSTALL_PREFIX}\")
if(_plenoptic_prefix STREQUAL \"/usr\")
  set(_plenoptic_confdir /etc/povray-plenoptic)
else()
  set(_plenoptic_confdir \"\${_plenoptic_prefix}/etc/povray-plenoptic\")
endif()
file(INSTALL DESTINATION \"\${_plenoptic_confdir}\" TYPE FILE
     FILES \"${POVRAY_CONF_DIR}/povray.ini\" \"${POVRAY_CONF_DIR}/povray.conf\")")

# --- The Debian package (tools/package: cpack -G DEB) ------------------------------------
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME povray-plenoptic)
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_VENDOR "povray-plenoptic developers")
set(CPACK_PACKAGE_CONTACT "povray-plenoptic developers")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "povray-plenoptic developers")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "POV-Ray 3.7 with a native plenoptic (light-field) camera")
set(CPACK_PACKAGE_DESCRIPTION "POV-Ray 3.7 (built from Debian's povray source package) with a
camera { plenoptic ... } that renders raw lenslet images of complex 3-D scenes for light-field
research: main lens, microlens array and sensor set in the scene file, and exact ground truth
(camera model, microimage lattice, depth map) written beside every image.

Installs povray-plenoptic beside Debian's povray (no shared file or command), the
forward-projection tool plenoptic-project and the light-field decoder plenoptic-decode.")
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # povray-plenoptic_<version>_<arch>.deb
# Shared libraries of the two binaries from dpkg-shlibdeps; the Python tools' modules by hand
# (python/plenoptic_lf imports numpy, scipy, PIL, OpenImageIO and jsonschema; tomllib: 3.11).
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "python3 (>= 3.11), python3-numpy, python3-scipy, python3-pil, python3-openimageio, python3-jsonschema")
# plenoptic_lf.calibration (the calibration loop, docs/calibration-loop.md) calibrates with OpenCV.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-opencv")
# Installed with the prefix /usr into a staging DESTDIR, so the configuration lands in /etc.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
# The files under /etc are the administrator's to edit: conffiles, kept on upgrade.
file(WRITE "${CMAKE_BINARY_DIR}/generated/deb/conffiles"
     "/etc/povray-plenoptic/povray.conf\n/etc/povray-plenoptic/povray.ini\n")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA "${CMAKE_BINARY_DIR}/generated/deb/conffiles")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_PACKAGE_DIRECTORY "${CMAKE_BINARY_DIR}/package")
include(CPack)
