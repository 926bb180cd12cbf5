#!/usr/bin/env bash
# Fuzzes every reader (tape, model, frd, csv, tfns, series, schedule), and the transfer matrix
# and state model on random shapes of data (shapes: at most FUZZ_SHAPES_RUNS, default 1000,
# executions), with libFuzzer under
# AddressSanitizer and UndefinedBehaviorSanitizer: configures build-fuzz/ with clang
# (-DFRALAB_FUZZ=ON), builds the fuzz_<reader> executables and runs each for RUNS executions
# (default 100000) from the seed corpus
# tests/fuzz/corpus/<reader>. A crash stops with the input kept in build-fuzz/crashes/<reader>/
# (add it to tests/fuzz/regressions/<reader>/ once fixed: fuzz_regression_test replays it).
# Prints, per reader, executions, seconds and crashes; exits non-zero on any crash.
# FUZZ_STEP=build only configures and builds; FUZZ_STEP=run only runs (the build already there):
# the test command builds once and runs the readers as separate tests, two at a time on two cores.
# Usage: fuzz.sh [RUNS] [READER...]
set -uo pipefail
cd "$(dirname "$0")/.."
runs=${1:-100000}
# A fixed seed makes the ctest run reproducible (the same inputs every time); FUZZ_SEED=0 lets
# libFuzzer pick one (exploring further, as a long run by hand should).
seed=${FUZZ_SEED:-1}
shift || true
readers=("$@")
[ ${#readers[@]} -eq 0 ] && readers=(tape model frd csv tfns series schedule shapes)
step=${FUZZ_STEP:-all}
if [ "$step" != run ]; then
  # Ninja for a new folder when it is there (the libraries' compiles overlap: 113 s instead of
  # 144 s on two cores); an existing folder keeps its generator.
  gen=()
  [ -f build-fuzz/CMakeCache.txt ] || ! command -v ninja >/dev/null || gen=(-G Ninja)
  CC=clang CXX=clang++ cmake "${gen[@]}" -S . -B build-fuzz -DFRALAB_FUZZ=ON \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null || exit 2
  targets=()
  for r in "${readers[@]}"; do targets+=("fuzz_$r"); done
  cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]}" >build-fuzz/build.log 2>&1 ||
    { tail -30 build-fuzz/build.log; exit 2; }
  [ "$step" = build ] && exit 0
fi
bad=0
for r in "${readers[@]}"; do
  [ -x build-fuzz/bin/fuzz_"$r" ] || { echo "fuzz $r: build-fuzz/bin/fuzz_$r is not built"; exit 2; }
  # A "shapes" input builds a whole state model (up to 8 x 8 paths, 0.1-1 s optimised, tens of
  # seconds under the sanitizers for the largest, and 150-200 s for one of them on a busy
  # machine): fewer runs, a longer timeout.
  n=$runs timeout=20
  if [ "$r" = shapes ]; then
    n=$((runs < ${FUZZ_SHAPES_RUNS:-1000} ? runs : ${FUZZ_SHAPES_RUNS:-1000})) timeout=600
  fi
  work=$(mktemp -d)
  cp tests/fuzz/corpus/"$r"/* "$work"/
  mkdir -p build-fuzz/crashes/"$r"
  t0=$(date +%s)
  ASAN_OPTIONS=detect_leaks=0:allocator_may_return_null=1 \
    build-fuzz/bin/fuzz_"$r" -runs="$n" -seed="$seed" -max_len=16384 -rss_limit_mb=2048 -timeout="$timeout" \
    -artifact_prefix=build-fuzz/crashes/"$r"/ "$work" >build-fuzz/fuzz_"$r".log 2>&1
  rc=$?
  t1=$(date +%s)
  execs=$(grep -o 'Done [0-9]* runs' build-fuzz/fuzz_"$r".log | grep -o '[0-9]*' | tail -1)
  printf 'fuzz %-5s: %s executions in %d s, %s\n' "$r" "${execs:-?}" "$((t1 - t0))" \
    "$([ $rc -eq 0 ] && echo "no crash" || echo "CRASH (rc $rc): see build-fuzz/fuzz_$r.log")"
  [ $rc -eq 0 ] || { bad=1; grep -m5 -E "ERROR|SUMMARY|runtime error|terminate" build-fuzz/fuzz_"$r".log; }
  rm -rf "$work"
done
exit $bad
