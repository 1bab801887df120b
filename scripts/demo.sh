#!/usr/bin/env bash
# `make demo`: builds, simulates the embedded default world (the office, with odometry drift and
# the true trajectory as the loop closure), plays it through launch/demo.launch headless and
# faster than real time, saves the map through ~save_map, and compares every merger on the same
# bag with linemap_batch. Results go to output/demo/.
#   DATASET=intel  the same on ../shared/datasets (raw Intel log, odometry poses, corrected
#                  trajectory as the loop closures) into output/intel/
#   WORLD=config/worlds/loop.yaml  another simulated world
#   RATE=20        playback rate of the bag
set -euo pipefail
source "$(dirname "$0")/env.sh"
"$(dirname "$0")/build.sh" >/dev/null
linemap_source_devel
cd "$LINEMAP_ROOT"

dataset="${DATASET:-sim}"
rate="${RATE:-20}"
datasets="$LINEMAP_ROOT/../shared/datasets"

if [ "$dataset" = "intel" ]; then
  for f in intel.clf.bz2 intel-corrected.log.gz; do
    [ -f "$datasets/$f" ] || { echo "demo: DATASET=intel needs $datasets/$f (missing)" >&2; exit 1; }
  done
  out="$LINEMAP_ROOT/output/intel"
  bag="$out/intel.bag"
  mkdir -p "$out"
  if [ ! -f "$bag" ]; then
    rosrun line_map_eval carmen_to_bag "$datasets/intel.clf.bz2" "$bag" \
      --corrected "$datasets/intel-corrected.log.gz" --every 50
  fi
  batch_input=("$datasets/intel.clf.bz2" --corrected "$datasets/intel-corrected.log.gz")
else
  world="${WORLD:-config/worlds/office.yaml}"
  name="$(basename "$world" .yaml)"
  out="$LINEMAP_ROOT/output/demo"
  bag="$out/$name.bag"
  mkdir -p "$out"
  if [ ! -f "$bag" ] || [ "$world" -nt "$bag" ]; then
    rosrun line_map_eval simulate_world "$world" "$bag" --seed 1
  fi
  batch_input=("$bag")
fi

# 1. The nodelet pipeline on the bag, as a user would run it (launch/demo.launch, headless).
echo "demo: playing $(basename "$bag") through launch/demo.launch at ${rate}x"
log="$out/roslaunch.log"
roslaunch "$LINEMAP_ROOT/launch/demo.launch" bag:="$bag" rate:="$rate" output:=log >"$log" 2>&1 &
launch_pid=$!
stop_ros() {
  kill -INT "$launch_pid" 2>/dev/null || true
  wait "$launch_pid" 2>/dev/null || true
}
trap stop_ros EXIT
# roslaunch reports when the player has played the whole bag.
for _ in $(seq 1 2400); do
  grep -q 'player-[0-9]*\] process has finished' "$log" && break
  kill -0 "$launch_pid" 2>/dev/null || { echo "demo: roslaunch stopped early, see $log" >&2; exit 1; }
  sleep 0.5
done
sleep 3  # the last keyframes and the final trajectory reach the map
map_file="$out/map.yaml"
if rosservice call /line_map_merging/save_map "path: '$map_file'" >"$out/save_map.log" 2>&1; then
  echo "demo: saved the nodelet's map to ${map_file#$LINEMAP_ROOT/}"
else
  echo "demo: ~save_map failed (see $out/save_map.log)" >&2
fi
rostopic echo -n 1 /map_quality >"$out/map_quality.txt" 2>/dev/null &
echo_pid=$!
sleep 3
kill "$echo_pid" 2>/dev/null || true
stop_ros
trap - EXIT

# 2. Every merger on the same data, with figures and the comparison table.
echo
rosrun line_map_eval linemap_batch "${batch_input[@]}" --out "$out/batch"

echo
echo "demo: results in ${out#$LINEMAP_ROOT/}/"
if [ -s "$out/map_quality.txt" ]; then
  echo "  nodelet pipeline: $(grep -E '^(quality|segment_count):' "$out/map_quality.txt" | tr '\n' ' ')"
fi
echo "  ${out#$LINEMAP_ROOT/}/batch/report.md     comparison table (also report.json)"
echo "  ${out#$LINEMAP_ROOT/}/batch/<merger>/map.{svg,pdf,png}   figures"
