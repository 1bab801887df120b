#!/usr/bin/env bash
# Builds and runs every gtest and rostest, then prints `N passed, N failed[, N skipped]`.
set -euo pipefail
source "$(dirname "$0")/env.sh"
"$(dirname "$0")/build.sh" all tests
results="$BUILD_DIR/build/test_results"
rm -rf "$results"
cd "$LINEMAP_ROOT"
# catkin's run_tests exits 0 even when tests fail: the verdict comes from the result files.
catkin_make --source "$LINEMAP_ROOT" --build "$BUILD_DIR/build" -DCATKIN_DEVEL_PREFIX="$BUILD_DIR/devel" \
  -DCATKIN_WHITELIST_PACKAGES="${PACKAGES:-}" run_tests -j1 ${TEST_TARGET_ARGS:-} || true
python3 "$LINEMAP_ROOT/scripts/test_summary.py" "$results"
