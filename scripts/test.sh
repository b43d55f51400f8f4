#!/usr/bin/env bash
# Installs dependencies, builds and runs every test.
#   scripts/test.sh              Release build in build/
#   scripts/test.sh --sanitize   AddressSanitizer + UndefinedBehaviorSanitizer build in build-asan/
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ "${1:-}" = "--sanitize" ]; then
  bash "$here/scripts/build.sh" "$here/build-asan" -DCOAXID_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCOAXID_BUILD_BENCH=OFF
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  cd "$here/build-asan"
else
  bash "$here/scripts/build.sh" "$here/build"
  cd "$here/build"
fi
ctest --output-on-failure -j"$(nproc)"
