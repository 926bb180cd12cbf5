#!/usr/bin/env bash
# The README's main command: installs dependencies, builds, and runs the J85 lab at its default
# operating point (95 % N/Nmax) end to end. Extra arguments go to `fralab run`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# What the lab runs, and only that: the driver and the module executables it starts (the tests,
# benchmarks and fuzz seeds are the test command's).
bash scripts/build.sh fralab
exec build/bin/fralab run --out "${FRALAB_OUT:-out/lab}" "$@"
