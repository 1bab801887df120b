#!/usr/bin/env bash
# `make demo`: builds, simulates the embedded default world (the office, with odometry drift and
# the true trajectory as the loop closure), plays it through launch/demo.launch headless and
# faster than real time, saves the map through ~save_map, and compares every merger on the same
# bag with linemap_batch. Results go to output/demo/.
#   DATASET=intel  the same on ../shared/datasets from the raw Intel log alone (scans and odometry;
#                  our laser SLAM closes the loops, its relations error is printed) into output/intel/
#   WORLD=config/worlds/loop.yaml  another simulated world
#   RATE=20        playback rate of the bag
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$LINEMAP_ROOT"
export LINEMAP_QUIET=1
# Only what the demo runs: the three nodelets, the tools it calls and the messages (rostopic and
# rosservice need their python side); not the benchmarks and tests of `make build` / `make test`.
LINEMAP_BUILD_WHAT="the three nodelets and the demo's tools" "$(dirname "$0")/build.sh" line_extraction_nodelet line_map_merging_nodelet line_map_eval_nodelet \
  line_map_merging_slam_nodelet simulate_world carmen_to_bag linemap_batch line_map_msgs_generate_messages
linemap_source_devel

dataset="${DATASET:-sim}"
rate="${RATE:-20}"
datasets="$LINEMAP_ROOT/../shared/datasets"
rel() { echo "${1#"$LINEMAP_ROOT"/}"; }

if [ "$dataset" = "intel" ]; then
  for f in intel.clf.bz2 intel.relations; do
    [ -f "$datasets/$f" ] || { echo "demo: DATASET=intel needs $datasets/$f (missing)" >&2; exit 1; }
  done
  out="$LINEMAP_ROOT/output/intel"
  bag="$out/intel_raw.bag"
  mkdir -p "$out"
  if [ ! -f "$bag" ]; then
    linemap_step "converting: the Intel Research Lab raw log (scans and odometry only) -> $(rel "$bag")" \
      "$out/carmen_to_bag.log" "" rosrun line_map_eval carmen_to_bag "$datasets/intel.clf.bz2" "$bag" --no-progress
  else
    echo "converting: $(rel "$bag") is there already"
  fi
  # The trajectory comes from our laser SLAM (config/slam.yaml), live and in the batch tool.
  batch_input=("$datasets/intel.clf.bz2" --slam --relations "$datasets/intel.relations")
  launch_args=(slam:=true)
else
  world="${WORLD:-config/worlds/office.yaml}"
  name="$(basename "$world" .yaml)"
  out="$LINEMAP_ROOT/output/demo"
  bag="$out/$name.bag"
  mkdir -p "$out"
  if [ ! -f "$bag" ] || [ "$world" -nt "$bag" ]; then
    linemap_step "simulating: the $name world ($world; drifting odometry, the true trajectory as the loop closure) -> $(rel "$bag")" \
      "$out/simulate_world.log" "" rosrun line_map_eval simulate_world "$world" "$bag" --seed 1 --no-progress
  else
    echo "simulating: $(rel "$bag") is up to date with $world"
  fi
  batch_input=("$bag")
fi

# 1. The nodelet pipeline on the bag, as a user would run it (launch/demo.launch, headless).
log="$out/roslaunch.log"
echo "playing: $(basename "$bag") through launch/demo.launch (the three nodelets) at ${rate}x real time (log: $(rel "$log"))"
start=$SECONDS
roslaunch "$LINEMAP_ROOT/launch/demo.launch" bag:="$bag" rate:="$rate" output:=log ${launch_args[@]+"${launch_args[@]}"} >"$log" 2>&1 &
launch_pid=$!
stop_ros() {
  kill -INT "$launch_pid" 2>/dev/null || true
  wait "$launch_pid" 2>/dev/null || true
}
trap stop_ros EXIT
# roslaunch reports when the player has played the whole bag.
until grep -q 'player-[0-9]*\] process has finished' "$log"; do
  kill -0 "$launch_pid" 2>/dev/null || { echo "playing: roslaunch stopped early; the last lines of $(rel "$log"):" >&2; tail -n 30 "$log" >&2; exit 1; }
  sleep 0.5
done
# The nodelets then finish the last scans and the trajectory: the evaluator's map_quality (latched)
# stops changing once they have; read it until two readings 2 s apart agree.
quality_file="$out/map_quality.txt"
previous=""
for _ in $(seq 60); do
  current="$(timeout 30 rostopic echo -n 1 /map_quality 2>/dev/null || true)"
  [ -n "$current" ] && [ "$current" = "$previous" ] && break
  previous="$current"
  sleep 2
done
printf '%s\n' "$current" >"$quality_file"
map_file="$out/map.yaml"
if ! rosservice call /line_map_merging/save_map "path: '$map_file'" >"$out/save_map.log" 2>&1; then
  echo "playing: ~save_map failed (see $(rel "$out/save_map.log"))" >&2
fi
stop_ros
trap - EXIT
echo "playing: done in $((SECONDS - start)) s"

# 2. Every merger on the same data, with figures and the comparison table.
echo "comparing: every merger on the same data with linemap_batch (figures and report in $(rel "$out/batch")/)"
echo
rosrun line_map_eval linemap_batch "${batch_input[@]}" --out "$out/batch"
echo

field() { sed -n "s/^$1: //p" "$quality_file" | head -n 1; }
echo "results in $(rel "$out")/:"
if [ -n "$(field quality)" ]; then
  live_kf="$(sed -n 's/^keyframe_count: //p' "$map_file" 2>/dev/null | head -n 1)"
  # The batch table's cae row, to set the live figure beside it.
  read -r b_q b_e b_s b_k < <(python3 -c 'import json,sys; m=json.load(open(sys.argv[1]))["mergers"].get("cae", {})
print(m.get("quality_pct", "nan"), m.get("error_mm", "nan"), m.get("map_segments", "?"), m.get("scans", "?"))' \
    "$out/batch/report.json" 2>/dev/null || echo "nan nan ? ?")
  printf '  the nodelet pipeline (cae, live at %sx): quality %.2f %%, error %.2f mm, %s map segments from %s keyframes\n' \
    "$rate" "$(field quality)" "$(awk -v e="$(field error)" 'BEGIN { print 1000 * e }')" "$(field segment_count)" "${live_kf:-?}"
  printf '  the batch table'"'"'s cae row:             quality %.2f %%, error %.2f mm, %s map segments from %s keyframes\n' \
    "$b_q" "$b_e" "$b_s" "$b_k"
  if [ "${live_kf:-}" = "$b_k" ] && [ "$(field segment_count)" = "$b_s" ]; then
    echo "    same keyframes, same map: the quality differs only through the lookup table, which the evaluator"
    echo "    nodelet builds from the scans as it registered them live (the batch tool from the recorded poses)"
  else
    echo "    other keyframes, so another map: the nodelets take keyframes as scans and tf arrive while the bag"
    echo "    plays (late or dropped scans under load: $(rel "$log")), the batch tool from the recorded poses"
  fi
  printf '  %-44s %s\n' "$(rel "$map_file")" "the nodelet pipeline's map (~save_map)"
fi
printf '  %-44s %s\n' "$(rel "$out")/batch/report.md" "the full comparison table (also report.json)"
printf '  %-44s %s\n' "$(rel "$out")/batch/<merger>/map.{svg,pdf,png}" "the figures, per merger"
