#!/usr/bin/env bash
# Configures and builds coaxid. Usage: scripts/build.sh [BUILD_DIR] [extra cmake args...]
# COAXID_BUILD_TARGETS="a b" builds only those targets (default: all).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$here/build}"
shift || true
bash "$here/scripts/install-deps.sh"
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@" > "$build.cmake.log" 2>&1 \
  || { cat "$build.cmake.log"; exit 1; }
targets=()
for t in ${COAXID_BUILD_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$build" -j"$(nproc)" "${targets[@]}"
