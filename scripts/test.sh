#!/usr/bin/env bash
# The README's test command: installs dependencies, builds, and runs every test with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test
# In CI (CI=true) a compiler warning fails the build.
[ "${CI:-}" = true ] && export FRALAB_WERROR=ON
bash scripts/build.sh
# One test more than cores: the integration tests leave part of a core idle while their processes
# wait for each other.
cd build && ctest --output-on-failure -j"$(($(nproc) + 1))" "$@"
