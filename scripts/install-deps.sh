#!/usr/bin/env bash
# The only place that installs packages (Debian 12). Idempotent: installs only what is missing.
# Used by the Makefile (make demo / make test) and therefore by CI.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libbullet-dev libbullet-extras-dev liburdfdom-dev libassimp-dev
  libtinyxml-dev libconsole-bridge-dev
  libopencv-dev libapriltag-dev libosmesa6-dev libimgui-dev libglfw3-dev libegl-dev
  libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev libcli11-dev
  ffmpeg xvfb xauth imagemagick
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
