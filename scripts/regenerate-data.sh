#!/usr/bin/env bash
# Regenerates the shipped simulated logs in data/glmav/ from their scenario
# files and seeds (configs/scenarios/), with the reference vehicle. `coaxid
# demo` re-simulates them and reports whether they are reproduced exactly.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
coaxid="${COAXID:-$here/build/coaxid}"
mkdir -p "$here/data/glmav"
for name in balance balance_points flight flight_3211 balance_wake; do
  "$coaxid" simulate --config="$here/configs/glmav.yaml" \
    --scenario="$here/configs/scenarios/$name.yaml" \
    --out="$here/data/glmav/$name.csv" --truth="$here/data/glmav/$name.truth.json"
done
