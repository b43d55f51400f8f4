#!/usr/bin/env bash
# The main job on a fresh machine: install dependencies, build, and run
# `coaxid demo` on the shipped data. Output folder: $1 (default demo-out/).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$here/demo-out}"
bash "$here/scripts/build.sh" "$here/build"
"$here/build/coaxid" demo --out="$out"
