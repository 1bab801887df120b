#!/usr/bin/env bash
# libFuzzer targets of the ROS-free cores, built with clang++ straight from the core sources
# (ASan + UBSan), outside catkin.
#   scripts/fuzz.sh build                 builds $BUILD_DIR/fuzz/bin/fuzz_<target>
#   scripts/fuzz.sh run [target...]       fuzzes each target FUZZ_SECONDS (default 60) on FUZZ_JOBS
#                                         workers (default 1); corpus in $BUILD_DIR/fuzz/corpus/<target>,
#                                         crashes in $BUILD_DIR/fuzz/crashes/<target>
#   scripts/fuzz.sh test <junit_dir>      replays test/fuzz_regressions/<target>/* and fuzzes each target
#                                         FUZZ_TEST_SECONDS (default 10); one JUnit test case per target
# Targets: extractors merging map_file carmen.
#
# FUZZ_CAMPAIGN=1 selects the campaign build for long runs (bin and obj under
# $BUILD_DIR/fuzz/campaign; corpus and crashes shared with the default build). The default -O1
# build stays what `make test` uses. The campaign build differs in three ways, none of which
# removes a check: ASan and UBSan stay on in every source.
#  - -O2 instead of -O1;
#  - UBSan's checks left out of the Eigen headers (scripts/fuzz_ubsan_ignorelist.txt; ASan still
#    instruments them): with them, Eigen's 2-D expression templates are too big for the inliner
#    and every Vec2 dot product became a chain of calls (half the time of ransac, em, wsac_ge);
#  - no comparison tracing (-fsanitize-coverage=trace-cmp) in the numeric core sources
#    (line_extraction/src, line_map_merging/src but map_file.cpp): at -O2 every inner-loop
#    iteration called __sanitizer_cov_trace_cmp8 (47 % of the extractors target's time), while
#    their branches hang on floating-point comparisons, which trace-cmp does not see. Edge
#    coverage stays; the harnesses and the parsers (map_file.cpp, carmen_log.cpp) keep trace-cmp.
# It also runs with ASAN_OPTIONS malloc_context_size=5 (allocation stacks of 5 frames, not 30, in
# a report) unless ASAN_OPTIONS sets it.
# Campaign of 2026-11-23 with it (one core, README "Fuzzing" has the command): extractors 940,840
# executions (870/s), merging 3,026,733 (3,149/s), map_file 1,653,584 (1,720/s), carmen 3,565,564
# (4,239/s), no crash; 10^7 per target would take ~3.2 h, 53, 97 and 39 min of one core.
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$LINEMAP_ROOT"
FUZZ_DIR="$BUILD_DIR/fuzz"
BIN_DIR="$FUZZ_DIR/bin" OBJ_DIR="$FUZZ_DIR/obj"
TARGETS=(extractors merging map_file carmen)
CXX="${FUZZ_CXX:-clang++}"
SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
OPT=(-O1) NO_TRACE_CMP="" NO_TRACE_CMP_EXCEPT=""
if [ "${FUZZ_CAMPAIGN:-0}" = 1 ]; then
  BIN_DIR="$FUZZ_DIR/campaign/bin" OBJ_DIR="$FUZZ_DIR/campaign/obj"
  OPT=(-O2 -fsanitize-ignorelist=scripts/fuzz_ubsan_ignorelist.txt)
  NO_TRACE_CMP='^line_(extraction|map_merging)/src/' NO_TRACE_CMP_EXCEPT='/map_file\.cpp$'
  case "${ASAN_OPTIONS:-}" in *malloc_context_size*) ;; *) export ASAN_OPTIONS="malloc_context_size=5${ASAN_OPTIONS:+:$ASAN_OPTIONS}" ;; esac
fi
CXXFLAGS=(-std=c++17 "${OPT[@]}" -g $SAN -I line_extraction/include -I line_map_merging/include
  -I line_map_eval/include -I line_extraction/fuzz -I /usr/include/eigen3 -DLINEMAP_FUZZING)
export ASAN_OPTIONS="halt_on_error=1:print_stacktrace=1:detect_leaks=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"

# Core sources of each target: the folders of the ROS-free libraries it links, as the CMakeLists
# build them. The merging targets take line_map_merging_core (mergers, online mapping, map grids);
# the laser SLAM and the localization (their own libraries, with Ceres) are not reached by any target.
core_sources() {
  case "$1" in
    extractors) extraction_core ;;
    merging | map_file)
      extraction_core
      find line_map_merging/src/mergers line_map_merging/src/online line_map_merging/src/map -name '*.cpp' | sort
      ;;
    carmen) find line_map_eval/src -name carmen_log.cpp ;;  # wherever line_map_eval keeps its datasets
  esac
}
# line_extraction_core: line_extraction/src but its ROS wrappers.
extraction_core() {
  find line_extraction/src -name '*.cpp' -not -path '*/ros/*' -not -name node.cpp -not -name nodelet.cpp | sort
}
target_source() {
  case "$1" in
    extractors) echo line_extraction/fuzz/fuzz_extractors.cpp ;;
    merging) echo line_map_merging/fuzz/fuzz_merging.cpp ;;
    map_file) echo line_map_merging/fuzz/fuzz_map_file.cpp ;;
    carmen) echo line_map_eval/fuzz/fuzz_carmen.cpp ;;
    *) echo "fuzz.sh: unknown target '$1' (known: ${TARGETS[*]})" >&2; return 1 ;;
  esac
}
target_libs() {
  case "$1" in
    merging | map_file) echo "-ltbb -lyaml-cpp" ;;
    carmen) echo "-lboost_iostreams -lz -lbz2" ;;
  esac
}

# Compiles one source to an object unless the object is newer than it and than every header.
compile() {
  local src="$1" obj="$OBJ_DIR/${1%.cpp}.o"
  mkdir -p "$(dirname "$obj")"
  if [ -f "$obj" ] && [ "$obj" -nt "$src" ] &&
    [ -z "$(find line_extraction/include line_map_merging/include line_map_eval/include -newer "$obj" -print -quit)" ]; then
    return 0
  fi
  echo "fuzz: compiling $src"
  local cov=(-fsanitize=fuzzer-no-link)
  if [ -n "${NO_TRACE_CMP:-}" ] && [[ $src =~ $NO_TRACE_CMP ]] && ! [[ $src =~ $NO_TRACE_CMP_EXCEPT ]]; then
    cov+=(-fno-sanitize-coverage=trace-cmp)
  fi
  # shellcheck disable=SC2086
  "$CXX" $CXXFLAGS_STR "${cov[@]}" -c "$src" -o "$obj"
}
export -f compile
export OBJ_DIR CXX NO_TRACE_CMP NO_TRACE_CMP_EXCEPT
export CXXFLAGS_STR="${CXXFLAGS[*]}"

build() {
  command -v "$CXX" > /dev/null || { echo "fuzz.sh: $CXX not found (scripts/setup.sh installs clang)" >&2; return 1; }
  # Objects of other flags (an older fuzz.sh) are stale whatever their time stamps.
  local flags="${CXXFLAGS[*]} ${NO_TRACE_CMP:-} ${NO_TRACE_CMP_EXCEPT:-}"
  if [ "$(cat "$OBJ_DIR/flags.txt" 2> /dev/null)" != "$flags" ]; then
    rm -rf "$OBJ_DIR" && mkdir -p "$OBJ_DIR" && echo "$flags" > "$OBJ_DIR/flags.txt"
  fi
  local srcs=()
  for t in "${TARGETS[@]}"; do
    mapfile -t -O "${#srcs[@]}" srcs < <(core_sources "$t")
    srcs+=("$(target_source "$t")")
  done
  printf '%s\n' "${srcs[@]}" | sort -u |
    xargs -P "${JOBS:-2}" -I{} bash -c 'compile "$1"' _ {} || return 1
  mkdir -p "$BIN_DIR"
  for t in "${TARGETS[@]}"; do
    local objs=()
    while read -r s; do objs+=("$OBJ_DIR/${s%.cpp}.o"); done < <(core_sources "$t"; target_source "$t")
    # shellcheck disable=SC2046
    "$CXX" "${CXXFLAGS[@]}" -fsanitize=fuzzer "${objs[@]}" $(target_libs "$t") -o "$BIN_DIR/fuzz_$t"
  done
}

# Fuzzes target $1 for $2 seconds; prints libFuzzer's last status line; fails on a crash.
fuzz_one() {
  local t="$1" seconds="$2" corpus="$FUZZ_DIR/corpus/$1" crashes="$FUZZ_DIR/crashes/$1"
  mkdir -p "$corpus" "$crashes"
  local log="$FUZZ_DIR/log_$t.txt"
  local jobs="${FUZZ_JOBS:-1}" extra=()
  if [ "$jobs" -gt 1 ]; then extra=(-fork="$jobs" -ignore_crashes=0); fi
  if [ "${3:-}" = test ]; then
    # make test: a fixed seed from the committed inputs only, so that a run is repeatable.
    corpus="$FUZZ_DIR/test_corpus/$t"
    rm -rf "$corpus" && mkdir -p "$corpus"
    extra+=(-seed=1)
  fi
  set +e
  "$BIN_DIR/fuzz_$t" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=20 -max_len=8192 \
    -print_final_stats=1 -artifact_prefix="$crashes/" "${extra[@]}" "$corpus" "test/fuzz_regressions/$t" > "$log" 2>&1
  local rc=$?
  set -e
  grep -E '^stat::number_of_executed_units|^stat::average_exec_per_sec|^#[0-9]+.*(DONE|pulse)' "$log" | tail -3 | sed "s/^/fuzz $t: /"
  if [ $rc -ne 0 ]; then
    echo "fuzz $t: FAILED (exit $rc), log $log, input in $crashes/" >&2
    grep -m1 -A25 -E '^==[0-9]+==ERROR|runtime error|deadly signal' "$log" >&2 || tail -30 "$log" >&2
    return 1
  fi
}

# Replays the committed regression inputs (no mutation).
replay_one() {
  local t="$1" dir="test/fuzz_regressions/$1"
  local files=()
  mapfile -t files < <(find "$dir" -maxdepth 1 -type f ! -name '*.md' 2> /dev/null | sort)
  [ ${#files[@]} -eq 0 ] && return 0
  "$BIN_DIR/fuzz_$t" -runs=1 "${files[@]}" > "$FUZZ_DIR/replay_$t.txt" 2>&1 ||
    { tail -40 "$FUZZ_DIR/replay_$t.txt" >&2; return 1; }
}

xml_escape() { sed -e 's/&/\&amp;/g' -e 's/</\&lt;/g' -e 's/>/\&gt;/g' -e 's/"/\&quot;/g'; }

cmd="${1:-run}"
shift || true
case "$cmd" in
  build) build ;;
  run)
    build
    sel=("$@")
    [ ${#sel[@]} -eq 0 ] && sel=("${TARGETS[@]}")
    failed=0
    for t in "${sel[@]}"; do fuzz_one "$t" "${FUZZ_SECONDS:-60}" || failed=1; done
    exit $failed
    ;;
  test)
    out="${1:?usage: fuzz.sh test <junit_dir>}"
    mkdir -p "$out"
    xml="$out/fuzz.xml"
    if ! build > "$out/fuzz_build.txt" 2>&1; then
      msg="$(tail -20 "$out/fuzz_build.txt" | xml_escape)"
      printf '<testsuite name="fuzz" tests="1" failures="1"><testcase classname="fuzz" name="build"><failure message="fuzz targets do not build">%s</failure></testcase></testsuite>\n' "$msg" > "$xml"
      echo "fuzz: build failed, see $out/fuzz_build.txt" >&2
      exit 0
    fi
    cases="" failures=0
    for t in "${TARGETS[@]}"; do
      if err="$( { replay_one "$t" && fuzz_one "$t" "${FUZZ_TEST_SECONDS:-10}" test; } 2>&1)"; then
        echo "$err"
        cases+="<testcase classname=\"fuzz\" name=\"fuzz_$t\"/>"
      else
        echo "$err" >&2
        failures=$((failures + 1))
        cases+="<testcase classname=\"fuzz\" name=\"fuzz_$t\"><failure message=\"fuzz_$t crashed\">$(echo "$err" | tail -40 | xml_escape)</failure></testcase>"
      fi
    done
    printf '<testsuite name="fuzz" tests="%d" failures="%d">%s</testsuite>\n' "${#TARGETS[@]}" "$failures" "$cases" > "$xml"
    ;;
  *) echo "usage: fuzz.sh build | run [target...] | test <junit_dir>" >&2; exit 2 ;;
esac
