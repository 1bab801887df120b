# Common environment of the workspace scripts; source it, do not run it.
# The Debian system python must come first: a pyenv python3 lacks catkin_pkg.
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:${PATH}"
LINEMAP_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# SANITIZE=1 (`make test SANITIZE=1`, `make check SANITIZE=1`): the ASan+UBSan build and its tests, in a
# directory of their own (.build-sanitize unless BUILD_DIR is set elsewhere).
if [ "${SANITIZE:-0}" = 1 ]; then
  case "${BUILD_DIR:-.build}" in .build | */.build) export BUILD_DIR=.build-sanitize ;; esac
  # Nodelets load into the uninstrumented nodelet manager: the ASan runtime then comes late (link order check
  # off); ROS and Python leak at exit by design, so leak checking stays off.
  export ASAN_OPTIONS="halt_on_error=1:print_stacktrace=1:detect_leaks=0:verify_asan_link_order=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
  export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
fi
BUILD_DIR="${BUILD_DIR:-${LINEMAP_ROOT}/.build}"
case "$BUILD_DIR" in /*) ;; *) BUILD_DIR="${LINEMAP_ROOT}/${BUILD_DIR}" ;; esac
export LINEMAP_ROOT BUILD_DIR

# After `source .build/devel/setup.bash` (the README's step) the caller's search paths hold this
# repository's own devel space and source tree. catkin bakes the CMAKE_PREFIX_PATH it is configured with
# into the install space's setup files, so the install would then chain the devel space: the scripts start
# from the caller's environment without the repository's paths (they source the devel space themselves).
linemap_strip_repository_paths() {
  local var value entry kept
  local -a entries
  for var in CMAKE_PREFIX_PATH ROS_PACKAGE_PATH LD_LIBRARY_PATH PYTHONPATH PKG_CONFIG_PATH; do
    value="${!var:-}"
    [ -n "$value" ] || continue
    kept=""
    IFS=: read -ra entries <<<"$value"
    for entry in "${entries[@]}"; do
      case "$entry" in
        "" | "$LINEMAP_ROOT" | "$LINEMAP_ROOT"/* | "$BUILD_DIR" | "$BUILD_DIR"/*) ;;
        *) kept="${kept:+$kept:}$entry" ;;
      esac
    done
    if [ -n "$kept" ]; then export "$var=$kept"; else unset "$var"; fi
  done
}
linemap_strip_repository_paths
export ROS_HOME="${ROS_HOME:-${BUILD_DIR}/ros_home}"
export ROS_LOG_DIR="${ROS_LOG_DIR:-${ROS_HOME}/log}"

# Sources the devel space (it is not `set -u` clean).
linemap_source_devel() {
  set +u
  # shellcheck disable=SC1091
  source "${BUILD_DIR}/devel/setup.bash"
  set -u
}

# Runs one step of `make demo` / `make test` with its output in a log: prints "LABEL (log: LOG)",
# then, on a terminal, the step's progress on that same line (PROGRESS: "build" = the build's
# percentage, "tests" = test targets run so far, "" = none), and finally "LABEL: done in N s".
# Without a terminal the two plain lines only. On failure: the log's last lines and its path;
# returns the command's status.
#   linemap_step LABEL LOG PROGRESS COMMAND [ARG...]
linemap_step() {
  local label="$1" log="$2" kind="$3"
  shift 3
  mkdir -p "$(dirname "$log")"
  local shown="${log#"$LINEMAP_ROOT"/}" start=$SECONDS rc=0
  if [ -t 1 ]; then
    "$@" >"$log" 2>&1 &
    local pid=$!
    while kill -0 "$pid" 2>/dev/null; do
      printf '\r\033[K%s %s(log: %s)' "$label" "$(_linemap_progress "$kind" "$log")" "$shown"
      sleep 0.5
    done
    wait "$pid" || rc=$?
    printf '\r\033[K'
  else
    echo "$label (log: $shown)"
    "$@" >"$log" 2>&1 || rc=$?
  fi
  if [ "$rc" -ne 0 ]; then
    echo "$label: FAILED (exit $rc) after $((SECONDS - start)) s; the last lines of $shown:" >&2
    tail -n 40 "$log" | sed 's/^/  | /' >&2
    echo "$label: full log: $log" >&2
    return "$rc"
  fi
  echo "$label: done in $((SECONDS - start)) s"
}

_linemap_progress() {
  case "$1" in
    build) grep -o '^\[ *[0-9]*%\]' "$2" 2>/dev/null | tail -n 1 | tr -d '[] ' | sed 's/$/ /' ;;
    tests)
      # One make target per gtest, rostest and launch check: _run_tests_<pkg>_<kind>_<name>.
      local leaf='_run_tests_[A-Za-z0-9_]*_(gtest|rostest|roslaunch-check)_'
      printf '%s of %s tests ' "$(grep -cE "Built target ${leaf}" "$2" 2>/dev/null || true)" \
        "$(find "$BUILD_DIR/build" -maxdepth 3 -type d -path '*/CMakeFiles/_run_tests_*' 2>/dev/null | grep -cE "/${leaf}" || true)"
      ;;
    # scripts/check.sh: one "gtest: <pkg>/<name>" line per test started, LINEMAP_GTESTS in all.
    gtests) printf '%s of %s tests ' "$(grep -c '^gtest: ' "$2" 2>/dev/null || true)" "${LINEMAP_GTESTS:-?}" ;;
  esac
}

# Prints the compiler warnings of the project's own sources found in a build log (none expected).
linemap_print_warnings() {
  local found
  found="$(grep -E "^${LINEMAP_ROOT}/[^ ]*:[0-9]+:[0-9]+: warning:" "$1" | sort -u || true)"
  if [ -n "$found" ]; then
    echo "build: $(echo "$found" | wc -l) compiler warning(s) in the project's sources:"
    echo "$found" | sed 's/^/  /'
  fi
}
