#!/usr/bin/env bash
# Installs fralab's build and run dependencies from Debian, idempotently: packages already present
# are not fetched again, and apt-get update runs only when something is missing.
# Usage: setup.sh [--test]
set -euo pipefail
PKGS=(build-essential cmake ninja-build pkg-config git
      liblcm-dev liblcm-bin liblcm-java default-jdk-headless libjchart2d-java
      libeigen3-dev libfftw3-dev libgtest-dev libgmock-dev libbenchmark-dev
      nlohmann-json3-dev libcli11-dev zlib1g-dev libmatio-dev libsndfile1-dev libcmark-gfm-dev
      libcmark-gfm-extensions-dev libboost-dev gnuplot-nox iproute2
      util-linux nftables)
# --test: also what only the tests use (Octave's invfreqs, the identifier's side-by-side check;
# Octave's control package: a state model fralab writes built with `ss` there).
# clang and its runtime: the fuzz build (libFuzzer, ASan, UBSan; scripts/fuzz.sh); clang-format:
# the format test (scripts/check_format.sh).
# chromium: report.html checked in a real browser (headless); python3-scipy: the .mat export
# loaded by scipy.io.loadmat.
if [ "${1:-}" = "--test" ]; then
  PKGS+=(octave octave-signal octave-control clang clang-format libclang-rt-14-dev chromium python3-scipy)
fi
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
