#!/usr/bin/env bash
# Figures for docs/validation.md: the lab's throughput, engine (sample-clock) time over wall time,
# on this machine, for the J85 at 95 % (4 inputs x 5 outputs, 44 pairs) measured by the report's
# stepped sine and by the auto campaign, with the live analysers grouped each way --analysers
# offers (pair: 28 processes, input: 4, 11: 4). Per run: engine s, wall s, speedup, the analysers,
# the largest 1-minute load average seen while it ran, and whether its frd files equal the first
# grouping's byte for byte (the curves must not depend on the grouping). Run after
# scripts/build.sh (about 15 min on two idle cores):
#   bash bench/throughput.sh [SEED]
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/load_watch.sh
B=${FRALAB_BIN:-build/bin}
seed=${1:-1}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| campaign | --analysers | engine s | wall s | speedup | max load | frd as pair's |"
echo "|---|---|---|---|---|---|---|"
for campaign in stepped auto; do
  for g in pair input 11; do
    d="$out/$campaign-$g"
    peak="$out/peak"
    with_peak_load "$peak" scripts/isolated.sh $B/fralab measure --engine j85_95 \
      --excitation "$campaign" --seed "$seed" --analysers "$g" --no-progress --out "$d" > /dev/null
    same=-
    if [ "$g" != pair ]; then
      same=yes
      for f in "$out/$campaign-pair"/frd/*.json; do
        cmp -s "$f" "$d/frd/$(basename "$f")" || same=no
      done
    fi
    /usr/bin/python3 - "$d/run.json" "$campaign" "$g" "$(cat "$peak")" "$same" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
e, w = r["engine_time_s"], r["wall_time_s"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {e:.0f} | {w:.1f} | {e / w:.0f}x | {sys.argv[4]} | {sys.argv[5]} |")
PY
  done
done
