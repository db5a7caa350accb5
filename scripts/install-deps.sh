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
  ffmpeg xvfb xauth xdotool imagemagick clang-format
  # The replay video: written through FFmpeg's libraries (libx264 preset), read through OpenCV.
  libavformat-dev libavcodec-dev libavutil-dev libswscale-dev
  # ROS recordings (inhand import): ROS 1 bags through Debian's rosbag_storage and message
  # headers; MCAP chunk codecs and rosbag2's sqlite3 for our own ROS 2 readers.
  librosbag-storage-dev libsensor-msgs-dev libgeometry-msgs-dev libtf2-msgs-dev libnav-msgs-dev
  librcpputils-dev librcutils-dev libboost-filesystem-dev libboost-regex-dev
  libzstd-dev liblz4-dev libsqlite3-dev libdeflate-dev
  # Image files: PNG and JPEG through their own libraries (not OpenCV's imgcodecs).
  libpng-dev libjpeg62-turbo-dev
  # The live ROS 1 node (roscpp), and the ROS core and rospy its test runs it against.
  libroscpp-dev libstd-msgs-dev python3-rosmaster python3-rospy
  # The official writers the importer is tested against: Debian's rosbag (Python).
  python3-rosbag python3-sensor-msgs python3-geometry-msgs python3-tf2-msgs python3-nav-msgs
  # The Python module (import inhand): pybind11 over the Tracker and sessions, NumPy arrays.
  pybind11-dev python3-dev python3-numpy
  # The evaluation's plots (app/python/inhand_plots.py).
  python3-matplotlib
)
# Node.js for the official MCAP / ROS 2 tools (npm packages below): Debian's, unless a Node.js
# with npm is installed already (its package conflicts with Debian's npm).
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  PACKAGES+=(nodejs npm)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

npm_tools() {
  # @mcap/core, @foxglove/rosmsg2-serialization, ... pinned by tests/ros/node/package-lock.json.
  local dir
  dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/tests/ros/node"
  if [ -f "$dir/node_modules/.package-lock.json" ] && cmp -s "$dir/package-lock.json" "$dir/node_modules/.inhand-lock"; then
    return 0
  fi
  echo "install-deps: npm ci in tests/ros/node"
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error) && cp "$dir/package-lock.json" "$dir/node_modules/.inhand-lock"
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  npm_tools
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
npm_tools
