#!/usr/bin/env bash
# Runs a command with the CPU saturated: one stress-ng CPU worker per core (Debian's stress-ng,
# installed by scripts/setup.sh) for as long as the command runs, e.g.
#   bash scripts/stress.sh make test
# STRESS_CPUS   workers (default: every core, `nproc`)
# STRESS_LOAD   percent load per worker (default 100)
# stress-ng runs in a process group of its own and is stopped (SIGTERM to the group, then SIGKILL)
# when this script exits for any reason, Ctrl-C included; its own --timeout (STRESS_TIMEOUT, default
# 4h) stops it should this script be killed with SIGKILL. Exits with the command's status.
set -euo pipefail
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:${PATH}"
if [ $# -eq 0 ]; then
  echo "usage: scripts/stress.sh COMMAND [ARG...]   (e.g. scripts/stress.sh make test)" >&2
  exit 2
fi
command -v stress-ng >/dev/null || { echo "stress.sh: stress-ng not found (scripts/setup.sh installs it)" >&2; exit 2; }

cpus="${STRESS_CPUS:-$(nproc)}"
load="${STRESS_LOAD:-100}"
stress_pid=""
stop_stress() {
  [ -n "$stress_pid" ] || return 0
  kill -TERM -- "-$stress_pid" 2>/dev/null || true
  for _ in $(seq 50); do
    kill -0 -- "-$stress_pid" 2>/dev/null || break
    sleep 0.1
  done
  kill -KILL -- "-$stress_pid" 2>/dev/null || true
  wait "$stress_pid" 2>/dev/null || true
  echo "stress: stress-ng stopped" >&2
  stress_pid=""
}
trap stop_stress EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# setsid: a group of its own (the script's background jobs are no group leaders, so setsid needs no
# fork and $! is stress-ng itself), which the trap stops as a whole.
setsid stress-ng --cpu "$cpus" --cpu-load "$load" --timeout "${STRESS_TIMEOUT:-4h}" --quiet >/dev/null 2>&1 &
stress_pid=$!
# The workers are up when stress-ng has forked them (its children exist).
for _ in $(seq 100); do
  workers="$(pgrep -c -P "$stress_pid" 2>/dev/null || true)"
  [ "${workers:-0}" -ge "$cpus" ] && break
  kill -0 "$stress_pid" 2>/dev/null || { echo "stress.sh: stress-ng exited at start" >&2; exit 1; }
  sleep 0.1
done
echo "stress: $cpus stress-ng CPU worker(s) at $load % (group $stress_pid) while running: $*" >&2

set +e
"$@"
rc=$?
set -e
exit "$rc"
