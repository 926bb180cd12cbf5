#!/usr/bin/env bash
# Figures for docs/validation.md: the lab's throughput on plants of a test cell's size, engine
# (sample-clock) time over wall time on this machine. Random machine-shaped plants
# (fralab-bench-plant: tests/util/random_machine.h) of 2x2, 4x16 and 8x32 channels (every pair
# X:O, u_X:X and u_X:O measured: 2x2 10 pairs, 4x16 132, 8x32 520), measured by the auto
# campaign with the analysers grouped by input (one instance per input) and, where the process
# count allows, one per pair. Per run: pairs, engine s, wall s, speedup and
# the largest 1-minute load average seen. Run after scripts/build.sh:
#   bash bench/throughput_sizes.sh [SIZES...]      # default: 2x2 4x16 8x32
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/load_watch.sh
B=${FRALAB_BIN:-build/bin}
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(2x2 4x16 8x32)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| plant | --analysers | pairs | engine s | wall s | speedup | max load |"
echo "|---|---|---|---|---|---|---|"
for size in "${sizes[@]}"; do
  ni=${size%x*}
  no=${size#*x}
  $B/fralab-bench-plant --inputs "$ni" --outputs "$no" --out "$out/plant-$size" > /dev/null
  groupings=(input)
  [ $((ni * no)) -le 8 ] && groupings=(pair input)
  for g in "${groupings[@]}"; do
    d="$out/$size-$g"
    peak="$out/peak"
    with_peak_load "$peak" scripts/isolated.sh $B/fralab measure \
      --engine "$out/plant-$size/engine.json" --excitation auto --analysers "$g" --no-progress \
      --out "$d" > /dev/null
    /usr/bin/python3 - "$d" "$size" "$g" "$(cat "$peak")" <<'PY'
import glob, json, sys
d = sys.argv[1]
r = json.load(open(f"{d}/run.json"))
e, w = r["engine_time_s"], r["wall_time_s"]
pairs = len(glob.glob(f"{d}/frd/*.json"))
print(f"| {sys.argv[2]} | {sys.argv[3]} | {pairs} | {e:.0f} | {w:.1f} | {e / w:.0f}x | {sys.argv[4]} |")
PY
  done
done
