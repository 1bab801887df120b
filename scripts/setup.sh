#!/usr/bin/env bash
# Installs the Debian 12 packages the workspace needs; does nothing when all are present.
set -euo pipefail
PACKAGES=(
  build-essential cmake pkg-config git
  catkin python3-catkin-pkg python3-rospkg
  libroscpp-dev libsensor-msgs-dev libvisualization-msgs-dev libnav-msgs-dev ros-nav-msgs
  ros-geometry-msgs ros-std-msgs libstd-msgs-dev
  libnodeletlib-dev libnodeletlib-tools libtf2-ros-dev libtf2-msgs-dev libtf2-geometry-msgs-dev
  librosbag-dev python3-rosbag libdiagnostic-updater-dev
  libgtest-dev librostest-dev python3-rostest rosbash python3-rosnode python3-roslaunch python3-rostopic python3-rosservice
  python3-sensor-msgs python3-visualization-msgs python3-nav-msgs python3-geometry-msgs python3-diagnostic-msgs
  libeigen3-dev libboost-dev libboost-iostreams-dev libtbb-dev libyaml-cpp-dev libcairo2-dev libceres-dev
  libbenchmark-dev libbz2-dev zlib1g-dev tf2-tools
  rviz xvfb xauth imagemagick libgl1-mesa-dri
  clang libclang-rt-14-dev
  stress-ng
)
missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
