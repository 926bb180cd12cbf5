#!/usr/bin/env bash
# Every benchmark the README quotes, in order. Run after scripts/build.sh:
#   bash bench/run_benchmarks.sh
set -euo pipefail
cd "$(dirname "$0")/.."
B=build/bin
echo "== plant (J85 95 %, 4 inputs, 1 kHz)"
$B/fralab-bench --benchmark_min_time=2
echo "== acquisition end to end: Wf, 0.1-100 Hz, 10 points/decade, stepped sine, all processes over LCM, --speed 0"
out=$(mktemp -d)
scripts/isolated.sh $B/fralab measure --engine j85_95 --input Wf --band 0.1:100 --points-per-decade 10 --out "$out/acq"
echo "== analyser kernel and offline analysis of that 15-channel tape"
FRALAB_BENCH_TAPE="$out/acq/tape.lcmlog" $B/fralab-bench-analyze --benchmark_min_time=1
echo "== identification: the report's transfer functions, one order-3 fit"
$B/fralab-bench-identify --benchmark_min_time=1
rm -rf "$out"
