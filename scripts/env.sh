# Common environment of the workspace scripts; source it, do not run it.
# The Debian system python must come first: a pyenv python3 lacks catkin_pkg.
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:${PATH}"
LINEMAP_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-${LINEMAP_ROOT}/.build}"
case "$BUILD_DIR" in /*) ;; *) BUILD_DIR="${LINEMAP_ROOT}/${BUILD_DIR}" ;; esac
export LINEMAP_ROOT BUILD_DIR
export ROS_HOME="${ROS_HOME:-${BUILD_DIR}/ros_home}"
export ROS_LOG_DIR="${ROS_LOG_DIR:-${ROS_HOME}/log}"

# Sources the devel space (it is not `set -u` clean).
linemap_source_devel() {
  set +u
  # shellcheck disable=SC1091
  source "${BUILD_DIR}/devel/setup.bash"
  set -u
}
