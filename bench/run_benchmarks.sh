#!/usr/bin/env bash
# Every benchmark docs/validation.md quotes, in order. Run after scripts/build.sh:
#   bash bench/run_benchmarks.sh
set -euo pipefail
cd "$(dirname "$0")/.."
B=build/bin
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "== plant (J85 95 %, 4 inputs, 1 kHz)"
$B/fralab-bench --benchmark_min_time=2
echo "== acquisition end to end: Wf, 0.1-100 Hz, 10 points/decade, stepped sine, all processes over LCM, --speed 0"
scripts/isolated.sh $B/fralab measure --engine j85_95 --input Wf --band 0.1:100 --points-per-decade 10 --out "$out/acq"
echo "== analyser kernel and offline analysis of that 15-channel tape"
FRALAB_BENCH_TAPE="$out/acq/tape.lcmlog" $B/fralab-bench-analyze --benchmark_min_time=1
echo "== identification: the report's transfer functions, one order-3 fit"
$B/fralab-bench-identify --benchmark_min_time=1
echo "== diagnosis of the 95 % J85 (four inputs) from a recorded tape: all 44 pairs analysed offline, then diagnosed"
scripts/isolated.sh $B/fralab measure --engine j85_95 --out "$out/j85" > /dev/null
pairs=()
for x in Wf A8 BLD IGV; do
  for o in N P3 DPP3 P5 T5; do pairs+=(--pair "$x:$o" --pair "u_$x:$o"); done
  pairs+=(--pair "u_$x:$x")
done
start=$(date +%s%N)
$B/fralab analyze --log "$out/j85/tape.lcmlog" "${pairs[@]}" --out "$out/offline" > /dev/null
$B/fralab diagnose --simulation j85_95_sim --measured "$out/offline" --out "$out/diag"
end=$(date +%s%N)
echo "diagnosis from tape: $(( (end - start) / 1000000 )) ms wall"
echo "== the auto campaign against the stepped sine, J85 at 70/85/95 % (about 15 min)"
bash bench/campaign_compare.sh
