#!/usr/bin/env bash
# `make check`: the fast tier. Builds the tests and runs every gtest of every package (the unit tests
# of the ROS-free cores) alone: no ROS master, no rostest, no fuzzing. Prints `N passed, N failed`
# and exits non-zero on any failure. PACKAGES="a;b" restricts it to those packages.
set -euo pipefail
source "$(dirname "$0")/env.sh"
export LINEMAP_QUIET="${LINEMAP_QUIET:-1}"
LINEMAP_BUILD_WHAT="the unit tests" "$(dirname "$0")/build.sh" tests
results="$BUILD_DIR/build/test_results"
rm -rf "$results"
cd "$LINEMAP_ROOT"
packages="${PACKAGES:-line_extraction;line_map_merging;line_map_eval}"
known="$(make -C "$BUILD_DIR/build" help)"
targets=()
for p in ${packages//;/ }; do
  # catkin's hidden per-package target: every gtest of the package, each writing its JUnit file.
  if grep -qx "\.\.\. _run_tests_${p}_gtest" <<<"$known"; then targets+=("_run_tests_${p}_gtest"); fi
done
# One test at a time (-j1), as `make test` runs them.
run_tests=(make -C "$BUILD_DIR/build" -j1 "${targets[@]}")
if [ "$LINEMAP_QUIET" = 1 ]; then
  LINEMAP_PROGRESS_KINDS=gtest linemap_step "testing: every gtest" "$BUILD_DIR/check.log" tests "${run_tests[@]}" || true
else
  "${run_tests[@]}" || true
fi
python3 "$LINEMAP_ROOT/scripts/test_summary.py" "$results"
