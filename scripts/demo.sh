#!/usr/bin/env bash
# `make demo`: builds, simulates the embedded default world, converts the Intel log
# when ../shared/datasets is present, and writes everything under output/.
# DATASET=intel runs the Intel part only; WORLD=config/worlds/<name>.yaml picks another world.
set -euo pipefail
source "$(dirname "$0")/env.sh"
"$(dirname "$0")/build.sh" >/dev/null
linemap_source_devel
cd "$LINEMAP_ROOT"

out="$LINEMAP_ROOT/output"
world="${WORLD:-config/worlds/office.yaml}"
datasets="$LINEMAP_ROOT/../shared/datasets"
dataset="${DATASET:-sim}"
mkdir -p "$out/demo"

written=()
if [ "$dataset" = "sim" ]; then
  name="$(basename "$world" .yaml)"
  bag="$out/demo/$name.bag"
  if [ ! -f "$bag" ] || [ "$world" -nt "$bag" ]; then
    rosrun line_map_eval simulate_world "$world" "$bag" --seed 1
  fi
  written+=("$bag" "${bag%.bag}.truth.yaml")
fi

if [ -d "$datasets" ]; then
  mkdir -p "$out/intel"
  bag="$out/intel/intel.bag"
  if [ ! -f "$bag" ]; then
    rosrun line_map_eval carmen_to_bag "$datasets/intel.clf.bz2" "$bag" \
      --corrected "$datasets/intel-corrected.log.gz" --every 50
  fi
  written+=("$bag")
elif [ "$dataset" = "intel" ]; then
  echo "demo: DATASET=intel needs $datasets (missing)" >&2
  exit 1
fi

echo
echo "demo: wrote"
for f in "${written[@]}"; do
  printf '  %s (%s)\n' "${f#$LINEMAP_ROOT/}" "$(du -h "$f" | cut -f1)"
done
