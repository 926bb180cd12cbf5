#!/usr/bin/env bash
# Configures and builds fralab (Release) into build/; executables land in build/bin/.
# Usage: build.sh [TARGET...]: only those targets and what they need (default: everything, the
# tests, benchmarks and fuzz seeds included).
set -euo pipefail
cd "$(dirname "$0")/.."
# FRALAB_WERROR=ON: warnings as errors (the test command sets it in CI); unset, the build keeps
# what it was configured with (so the lab's build after CI's does not rebuild everything).
# A new build folder uses Ninja when it is there (it schedules every target's compiles together,
# where Make waits for a library's link before the targets using it start: the lab's executables
# 144 s instead of 157 s on two cores); an existing one keeps the generator it was made with.
gen=()
[ -f build/CMakeCache.txt ] || ! command -v ninja >/dev/null || gen=(-G Ninja)
cmake "${gen[@]}" -S . -B build -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-Release}" \
  ${FRALAB_WERROR:+-DFRALAB_WERROR="$FRALAB_WERROR"} >/dev/null
if [ $# -gt 0 ]; then
  cmake --build build -j"$(nproc)" --target "$@"
else
  cmake --build build -j"$(nproc)"
fi
