# shellcheck shell=bash
# SPDX-License-Identifier: AGPL-3.0-or-later
# Up-front checks that what a stage needs is installed, naming the Debian package that provides
# each missing thing (instead of a late link or import failure). Sourced by tools/install-deps,
# tools/test, tools/sanitize-check and fuzz/run-ci. The packages and what each stage checks are
# listed once, in tools/lib/packages.
#
#   . tools/lib/require.sh
#   require_stage WHO STAGE...          every check tools/lib/packages lists for these stages;
#                                       returns 1 (after naming all that is missing) if any fails
#   require_packages [STAGE...]         the package names (all of them without a stage)
# or, one at a time, then require_report WHO:
#   require_command CMD PACKAGE
#   require_file PATH PACKAGE           PATH may be a glob: at least one match
#   require_python_module MODULE PACKAGE
#   require_compiler_file COMPILER FILE PACKAGE    FILE found by COMPILER -print-file-name
# REQUIRE_WARN=1 before a check makes a miss a warning only.

REQUIRE_LIST=${REQUIRE_LIST:-"$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/packages"}
REQUIRE_PYTHON=${REQUIRE_PYTHON:-/usr/bin/python3}
_require_missing=()
_require_missing_packages=()
_require_warnings=()

_require_miss() {  # _require_miss WHAT PACKAGE
  if [ "${REQUIRE_WARN:-0}" = 1 ]; then
    _require_warnings+=("$1 (Debian package: $2)")
  else
    _require_missing+=("$1 (Debian package: $2)")
    case " ${_require_missing_packages[*]} " in *" $2 "*) ;; *) _require_missing_packages+=("$2") ;; esac
  fi
}

require_command() {
  command -v "$1" >/dev/null 2>&1 || _require_miss "command '$1'" "$2"
}

require_file() {
  local f
  for f in $1; do  # unquoted: the glob expands; no match leaves the pattern itself
    [ -e "$f" ] && return 0
  done
  _require_miss "file $1" "$2"
}

require_python_module() {
  if [ ! -x "$REQUIRE_PYTHON" ]; then
    _require_miss "Python module '$1' ($REQUIRE_PYTHON is missing)" "$2"
  elif ! "$REQUIRE_PYTHON" -c "import $1" >/dev/null 2>&1; then
    _require_miss "Python module '$1' for $REQUIRE_PYTHON" "$2"
  fi
}

require_compiler_file() {  # the compiler prints the bare name back when it finds no such file
  local found
  if ! command -v "$1" >/dev/null 2>&1; then
    _require_miss "$2 (compiler '$1' is missing)" "$3"
    return 0
  fi
  found=$("$1" -print-file-name="$2" 2>/dev/null || true)
  case "$found" in /*) [ -e "$found" ] && return 0 ;; esac
  _require_miss "$2 for $1" "$3"
}

# The lines of the list that belong to one of the stages: "PACKAGE CHECK..." (no stages column).
_require_lines() {
  local want=" $* " package stages checks s
  while read -r package stages checks; do
    case "$package" in ''|'#'*) continue ;; esac
    if [ -z "${want// /}" ]; then echo "$package $checks"; continue; fi
    for s in ${stages//,/ }; do
      case "$want" in *" $s "*) echo "$package $checks"; break ;; esac
    done
  done < "$REQUIRE_LIST"
}

require_packages() {
  _require_lines "$@" | awk '{ print $1 }'
}

require_stage() {  # require_stage WHO STAGE...
  local who=$1 package checks check kind arg arch
  shift
  arch=$(uname -m)
  [ -f "$REQUIRE_LIST" ] || { echo "$who: error: no package list $REQUIRE_LIST" >&2; return 1; }
  while read -r package checks; do
    for check in $checks; do
      local REQUIRE_WARN=0
      case "$check" in '?'*) REQUIRE_WARN=1; check=${check#\?} ;; esac
      kind=${check%%:*}
      arg=${check#*:}
      arg=${arg//@ARCH@/$arch}
      case "$kind" in
        cmd) require_command "$arg" "$package" ;;
        file) require_file "$arg" "$package" ;;
        py) require_python_module "$arg" "$package" ;;
        cxx) require_compiler_file "${CXX:-c++}" "$arg" "$package" ;;
        clang) require_compiler_file clang++ "$arg" "$package" ;;
        *) echo "$who: error: unknown check '$check' for $package in $REQUIRE_LIST" >&2; return 1 ;;
      esac
    done
  done < <(_require_lines "$@")
  require_report "$who"
}

require_report() {  # require_report WHO: 0 when nothing is missing; resets the lists
  local who=$1 w m status=0
  for w in "${_require_warnings[@]}"; do echo "$who: warning: missing $w" >&2; done
  if [ ${#_require_missing[@]} -gt 0 ]; then
    for m in "${_require_missing[@]}"; do echo "$who: error: missing $m" >&2; done
    echo "$who: install with: tools/install-deps (or: apt-get install --no-install-recommends ${_require_missing_packages[*]})" >&2
    status=1
  fi
  _require_missing=()
  _require_missing_packages=()
  _require_warnings=()
  return $status
}
