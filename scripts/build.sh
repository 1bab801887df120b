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
# A build directory configured while the devel space was sourced chains it into the install space
# (env.sh): configure it again, now from the clean environment.
force_cmake=()
setup_util="$BUILD_DIR/build/catkin_generated/installspace/_setup_util.py"
if [ -f "$setup_util" ] && grep -E "^ *CMAKE_PREFIX_PATH = r'[^']*(${LINEMAP_ROOT}|${BUILD_DIR})" "$setup_util" >/dev/null; then
  force_cmake=(--force-cmake)
fi
build_cmd=(catkin_make ${force_cmake[@]+"${force_cmake[@]}"} --source "$LINEMAP_ROOT" --build "$BUILD_DIR/build"
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
