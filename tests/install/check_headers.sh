#!/usr/bin/env bash
# Every installed public header compiles on its own with Eigen and the standard library only:
# no Bullet, OpenCV, urdfdom, assimp, AprilTag, GL, ImGui or nlohmann header is reached.
# usage: check_headers.sh PREFIX CXX EIGEN_INCLUDE_DIR
set -uo pipefail
prefix=$1 cxx=$2 eigen=$3
forbidden='/(nlohmann|assimp|bullet|opencv4?|apriltag|urdf[a-z_]*|urdfdom[a-z_]*|tinyxml[0-9]*|console_bridge|GL|GLFW|EGL|imgui|HACD|ros[a-z0-9_]*)/'
headers=$(cd "$prefix/include" && find inhand -name '*.hpp' | sort)
[ -n "$headers" ] || { echo "no headers under $prefix/include"; exit 1; }
# One compiler run per header: the syntax check writes the list of headers it read (-MD).
check() {
  local h=$1 deps
  deps=$(mktemp)
  printf '#include <%s>\n' "$h" | "$cxx" -std=c++17 -x c++ -fsyntax-only -Wall -Wextra -Werror -MD -MF "$deps" \
    -I"$prefix/include" -I"$eigen" - || { echo "FAIL $h: does not compile on its own"; rm -f "$deps"; return 1; }
  local bad
  bad=$(tr ' \\' '\n\n' < "$deps" | grep -E "$forbidden")
  rm -f "$deps"
  if [ -n "$bad" ]; then echo "FAIL $h reaches: $bad"; return 1; fi
  echo "ok $h"
}
export -f check
export prefix cxx eigen forbidden
printf '%s\n' $headers | xargs -P "$(nproc)" -I{} bash -c 'check {}' > "${TMPDIR:-/tmp}/inhand-header-check.$$" 2>&1
status=$?
cat "${TMPDIR:-/tmp}/inhand-header-check.$$"; rm -f "${TMPDIR:-/tmp}/inhand-header-check.$$"
count=$(printf '%s\n' $headers | wc -l)
[ $status -eq 0 ] && echo "$count installed headers stand alone" || exit 1
