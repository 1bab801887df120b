#!/usr/bin/env bash
# Sanitizer checks outside catkin.
#   scripts/sanitize.sh tsan   builds line_map_merging/fuzz/tsan_mp_gma.cpp with ThreadSanitizer
#                              (clang++ -fsanitize=thread, straight from the core sources) and runs
#                              MP-GMA's parallel adjustment with 2 threads on ~10^4 leaves.
#                              libtbb is not instrumented, so LINEMAP_TSAN runs MP-GMA's parallel
#                              loops on std::threads there (same bodies; see mp_gma.cpp).
# (ASan + UBSan over the whole suite: `make test SANITIZE=1`.)
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$LINEMAP_ROOT"
case "${1:-tsan}" in
  tsan)
    out="$BUILD_DIR/tsan"
    mkdir -p "$out"
    # line_extraction_core and line_map_merging_core, as fuzz.sh takes them (no Ceres).
    mapfile -t srcs < <(find line_extraction/src -name '*.cpp' -not -path '*/ros/*' -not -name node.cpp \
      -not -name nodelet.cpp; find line_map_merging/src/mergers line_map_merging/src/online line_map_merging/src/map -name '*.cpp')
    echo "sanitize: building $out/tsan_mp_gma"
    clang++ -std=c++17 -O1 -g -fsanitize=thread -fno-omit-frame-pointer -DLINEMAP_TSAN -I line_extraction/include \
      -I line_map_merging/include -I /usr/include/eigen3 "${srcs[@]}" line_map_merging/fuzz/tsan_mp_gma.cpp \
      -ltbb -lyaml-cpp -o "$out/tsan_mp_gma"
    TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1${TSAN_OPTIONS:+:$TSAN_OPTIONS}" "$out/tsan_mp_gma"
    ;;
  *) echo "usage: sanitize.sh tsan" >&2; exit 2 ;;
esac
