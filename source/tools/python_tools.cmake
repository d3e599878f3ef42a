# SPDX-License-Identifier: AGPL-3.0-or-later
# Install rules of the Python tools, included by source/tools/CMakeLists.txt (a file of its own so
# that it can be read, and tried, apart from the C++ tools).
#
# The Python tools (python/plenoptic_lf): the package in P/lib/python3/dist-packages (Debian's path
# for /usr/bin/python3's modules) and one launcher P/bin/<tool> for each tool of the one table,
# python/pyproject.toml's [project.scripts] (pip's console scripts). write_launchers.py writes the
# launchers at configure time for the Python found here, which their first line names: they run
# under it whatever python3 comes first on PATH, and find the package relative to their own real
# path (a moved prefix keeps working; platform/install.cmake, docs/install.md).
if(EXISTS /usr/bin/python3 AND NOT Python3_EXECUTABLE)
  set(Python3_EXECUTABLE /usr/bin/python3)  # Debian's, which tools/install-deps equips
endif()
find_package(Python3 3.11 REQUIRED COMPONENTS Interpreter)  # 3.11: tomllib
set(_python_dir "${CMAKE_CURRENT_LIST_DIR}/../../python")
set(_launcher_dir "${CMAKE_CURRENT_BINARY_DIR}/launchers")
execute_process(
  COMMAND "${Python3_EXECUTABLE}" "${CMAKE_CURRENT_LIST_DIR}/write_launchers.py"
          --out "${_launcher_dir}" --python "${Python3_EXECUTABLE}" --packages lib/python3/dist-packages
  RESULT_VARIABLE _launchers_status OUTPUT_VARIABLE _launchers ERROR_VARIABLE _launchers_error
  OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT _launchers_status EQUAL 0)
  message(FATAL_ERROR "source/tools/write_launchers.py failed: ${_launchers_error}")
endif()
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${_python_dir}/pyproject.toml"
             "${CMAKE_CURRENT_LIST_DIR}/write_launchers.py" "${CMAKE_CURRENT_LIST_DIR}/launcher.py.in")
string(REPLACE "\n" ";" _launchers "${_launchers}")
foreach(_tool IN LISTS _launchers)
  install(PROGRAMS "${_launcher_dir}/${_tool}" DESTINATION bin)
endforeach()
# The modules the tools import (python/pyproject.toml's dependencies), checked here once: the
# launchers run under this Python.
execute_process(COMMAND "${Python3_EXECUTABLE}" -c "import numpy, scipy, PIL, OpenImageIO, jsonschema"
                RESULT_VARIABLE _modules_status OUTPUT_QUIET ERROR_VARIABLE _modules_error)
if(NOT _modules_status EQUAL 0)
  string(STRIP "${_modules_error}" _modules_error)
  string(REGEX REPLACE ".*\n" "" _modules_error "${_modules_error}")
  message(WARNING "${Python3_EXECUTABLE}, which the installed Python tools run under, lacks a module they import "
                  "(${_modules_error}): run tools/install-deps (Debian: python3-numpy python3-scipy python3-pil "
                  "python3-openimageio python3-jsonschema)")
endif()
install(DIRECTORY "${_python_dir}/plenoptic_lf" DESTINATION lib/python3/dist-packages
        PATTERN "__pycache__" EXCLUDE PATTERN "*.pyc" EXCLUDE
        PATTERN "metadata.schema.json" EXCLUDE)  # a link to docs/ in the source tree: the file itself
install(FILES "${CMAKE_CURRENT_LIST_DIR}/../../docs/metadata.schema.json"
        DESTINATION lib/python3/dist-packages/plenoptic_lf)
