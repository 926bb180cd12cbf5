#!/usr/bin/env bash
# Configures and builds fralab (Release) into build/; executables land in build/bin/.
# Usage: build.sh [TARGET...]: only those targets and what they need (default: everything, the
# tests, benchmarks and fuzz seeds included).
set -euo pipefail
cd "$(dirname "$0")/.."
# FRALAB_WERROR=ON: warnings as errors (the test command sets it in CI); unset, the build keeps
# what it was configured with (so the lab's build after CI's does not rebuild everything).
cmake -S . -B build -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-Release}" \
  ${FRALAB_WERROR:+-DFRALAB_WERROR="$FRALAB_WERROR"} >/dev/null
if [ $# -gt 0 ]; then
  cmake --build build -j"$(nproc)" --target "$@"
else
  cmake --build build -j"$(nproc)"
fi
