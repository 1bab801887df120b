#!/usr/bin/env bash
# Builds the catkin workspace (the repository root is the source space) into $BUILD_DIR.
# PACKAGES="a;b" restricts the build to those packages (catkin whitelist).
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$LINEMAP_ROOT"
mkdir -p "$BUILD_DIR"
catkin_make --source "$LINEMAP_ROOT" --build "$BUILD_DIR/build" \
  -DCATKIN_DEVEL_PREFIX="$BUILD_DIR/devel" -DCMAKE_BUILD_TYPE=Release \
  -DCATKIN_WHITELIST_PACKAGES="${PACKAGES:-}" ${CMAKE_ARGS:-} -j"${JOBS:-2}" "$@"
