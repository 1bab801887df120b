#!/usr/bin/env bash
# `make test`, the whole suite and what CI runs: builds everything, runs every gtest, rostest, launch check
# and the install check, replays and briefly runs the fuzzers, then prints `N passed, N failed[, N skipped]`.
set -euo pipefail
source "$(dirname "$0")/env.sh"
# The build's and the tests' output go to logs in $BUILD_DIR (build.log, test.log, fuzz.log); one line
# per step, the failures and the summary at the end. LINEMAP_QUIET=0 shows everything as it runs.
export LINEMAP_QUIET="${LINEMAP_QUIET:-1}"
LINEMAP_BUILD_WHAT="everything, tests included" "$(dirname "$0")/build.sh" all tests
results="$BUILD_DIR/build/test_results"
rm -rf "$results"
cd "$LINEMAP_ROOT"
# catkin's run_tests exits 0 even when tests fail: the verdict comes from the result files.
run_tests=(catkin_make --source "$LINEMAP_ROOT" --build "$BUILD_DIR/build" -DCATKIN_DEVEL_PREFIX="$BUILD_DIR/devel"
  -DCATKIN_WHITELIST_PACKAGES="${PACKAGES:-}" run_tests -j1 ${TEST_TARGET_ARGS:-})
if [ "$LINEMAP_QUIET" = 1 ]; then
  linemap_step "testing: every gtest and rostest" "$BUILD_DIR/test.log" tests "${run_tests[@]}" || true
else
  "${run_tests[@]}" || true
fi
# libFuzzer targets (full runs only; FUZZ_TEST=0 skips): replay test/fuzz_regressions, then fuzz each
# target FUZZ_TEST_SECONDS (default 10); one JUnit case per target in the results.
if [ -z "${PACKAGES:-}" ] && [ "${FUZZ_TEST:-1}" != 0 ]; then
  if [ "$LINEMAP_QUIET" = 1 ]; then
    linemap_step "fuzzing: the four libFuzzer targets ${FUZZ_TEST_SECONDS:-10} s each" "$BUILD_DIR/fuzz.log" "" \
      bash "$LINEMAP_ROOT/scripts/fuzz.sh" test "$results/fuzz" || true
  else
    bash "$LINEMAP_ROOT/scripts/fuzz.sh" test "$results/fuzz" || true
  fi
fi
python3 "$LINEMAP_ROOT/scripts/test_summary.py" "$results"
