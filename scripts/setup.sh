#!/usr/bin/env bash
# Installs the Debian 12 packages the workspace needs; does nothing when all are present.
set -euo pipefail
PACKAGES=(
  build-essential cmake pkg-config git
  catkin python3-catkin-pkg python3-rospkg
  libroscpp-dev libsensor-msgs-dev libvisualization-msgs-dev libnav-msgs-dev ros-nav-msgs
  ros-geometry-msgs ros-std-msgs libstd-msgs-dev
  libnodeletlib-dev libnodeletlib-tools python3-nodelet libtf2-ros-dev libtf2-msgs-dev libtf2-geometry-msgs-dev
  librosbag-dev python3-rosbag libdiagnostic-updater-dev
  libgtest-dev librostest-dev python3-rostest rosbash python3-rosnode python3-roslaunch python3-rostopic python3-rosservice
  python3-sensor-msgs python3-visualization-msgs python3-nav-msgs python3-geometry-msgs python3-diagnostic-msgs python3-std-srvs
  libeigen3-dev libboost-dev libboost-iostreams-dev libtbb-dev libyaml-cpp-dev libcairo2-dev libceres-dev
  libbenchmark-dev libbz2-dev zlib1g-dev tf2-tools libdxflib-dev nlohmann-json3-dev
  rviz xvfb xauth imagemagick libgl1-mesa-dri
  clang libclang-rt-14-dev
  stress-ng
  catkin-tools
)
missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  # Quiet for the tools' own use; one line for `make demo` / `make test`.
  [ "${LINEMAP_QUIET:-0}" = 1 ] && echo "installing: nothing, all ${#PACKAGES[@]} Debian packages are present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
source "$(dirname "$0")/env.sh"
log="$BUILD_DIR/setup.log"
mkdir -p "$BUILD_DIR"
echo "installing: ${#missing[@]} Debian packages with apt-get (log: ${log#"$LINEMAP_ROOT"/}): ${missing[*]}"
start=$SECONDS
if ! { $SUDO apt-get update -q && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"; } >"$log" 2>&1; then
  echo "installing: FAILED; the last lines of $log:" >&2
  tail -n 30 "$log" | sed 's/^/  | /' >&2
  exit 1
fi
echo "installing: done in $((SECONDS - start)) s"
