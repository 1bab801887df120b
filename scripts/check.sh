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
# Each gtest binary straight from its package directory, one at a time, as catkin's run_tests would
# run it but without a make and a python wrapper per test; a binary that ends without its JUnit file
# (a crash) gets one recording the failure.
run_gtests() {
  local p f name xml rc
  for p in ${packages//;/ }; do
    mkdir -p "$results/$p"
    for f in "$LINEMAP_ROOT/$p"/test/test_*.cpp; do
      [ -e "$f" ] || continue
      name="$(basename "$f" .cpp)"
      xml="$results/$p/gtest-$name.xml"
      echo "gtest: $p/$name"
      rc=0
      (cd "$LINEMAP_ROOT/$p" && "$BUILD_DIR/devel/lib/$p/$name" --gtest_output="xml:$xml") || rc=$?
      if [ ! -s "$xml" ]; then
        printf '<testsuite tests="1" failures="1"><testcase classname="%s" name="%s"><failure message="exit %s without a result file"/></testcase></testsuite>\n' \
          "$p" "$name" "$rc" >"$xml"
      fi
    done
  done
}
if [ "$LINEMAP_QUIET" = 1 ]; then
  LINEMAP_GTESTS="$(for p in ${packages//;/ }; do ls "$LINEMAP_ROOT/$p"/test/test_*.cpp 2>/dev/null; done | wc -l)" \
    linemap_step "testing: every gtest" "$BUILD_DIR/check.log" gtests run_gtests || true
else
  run_gtests || true
fi
python3 "$LINEMAP_ROOT/scripts/test_summary.py" "$results"
