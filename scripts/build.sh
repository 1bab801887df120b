#!/usr/bin/env bash
# Builds the catkin workspace (the repository root is the source space) into $BUILD_DIR.
# PACKAGES="a;b" restricts the build to those packages (catkin whitelist).
set -euo pipefail
# SANITIZE=1: ASan+UBSan build in its own directory (env.sh).
source "$(dirname "$0")/env.sh"
cd "$LINEMAP_ROOT"
mkdir -p "$BUILD_DIR"
san_args=()
if [ "${SANITIZE:-0}" = 1 ]; then
  san="-fsanitize=address,undefined -fno-omit-frame-pointer -g -O1"
  san_args=("-DCMAKE_CXX_FLAGS=$san" "-DCMAKE_C_FLAGS=$san" "-DCMAKE_CXX_FLAGS_RELEASE=" "-DCMAKE_C_FLAGS_RELEASE="
    "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" "-DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=address,undefined"
    "-DCMAKE_MODULE_LINKER_FLAGS=-fsanitize=address,undefined")
fi
build_cmd=(catkin_make --source "$LINEMAP_ROOT" --build "$BUILD_DIR/build"
  -DCATKIN_DEVEL_PREFIX="$BUILD_DIR/devel" -DCMAKE_BUILD_TYPE=Release
  -DCATKIN_WHITELIST_PACKAGES="${PACKAGES:-}" ${san_args[@]+"${san_args[@]}"} ${CMAKE_ARGS:-} -j"${JOBS:-2}" "$@")
# LINEMAP_QUIET=1 (make demo, make test): the build's output goes to $BUILD_DIR/build.log, one line
# (with the percentage on a terminal), the log's tail on failure; the project's own compiler
# warnings are printed after it.
if [ "${LINEMAP_QUIET:-0}" = 1 ]; then
  what="${LINEMAP_BUILD_WHAT:-the workspace${*:+ (targets $*)}}"
  linemap_step "building: $what into ${BUILD_DIR#"$LINEMAP_ROOT"/}" "$BUILD_DIR/build.log" build "${build_cmd[@]}"
  linemap_print_warnings "$BUILD_DIR/build.log"
else
  "${build_cmd[@]}"
fi
