#!/usr/bin/env bash
# Long flight logs (issue 15): wall time and peak memory of the estimators on
# simulated flights of 5, 20 and 60 minutes (the shipped flight scenario,
# 200 Hz, made longer) plus the shipped balance log, measured the way a user
# would: /usr/bin/time -v around the `coaxid` command (the EKF, with its
# smoother, on the flight alone: it takes no balance log; `discover`, the
# whole closing loop with every library candidate, on the flight alone too:
# issue 15 asks for it on a flight log). Prints a Markdown
# table on stdout; the logs and outputs go to $COAXID_LONG_DIR
# (default /tmp/coaxid-long) and are reused by later runs.
#
#   bench/long_flight.sh                       # output_error at 5, 20, 60 min
#   bench/long_flight.sh "ekf" "5 20"          # methods, minutes
#   bench/long_flight.sh discover "5 20"
#
# Run on an idle machine: the numbers are wall times.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
coaxid="${COAXID_BINARY:-$root/build/coaxid}"
methods="${1:-output_error}"
minutes="${2:-5 20 60}"
dir="${COAXID_LONG_DIR:-/tmp/coaxid-long}"
[[ -x "$coaxid" ]] || { echo "long_flight.sh: no $coaxid: run scripts/build.sh first" >&2; exit 1; }
[[ -x /usr/bin/time ]] || { echo "long_flight.sh: /usr/bin/time is missing (apt-get install time)" >&2; exit 1; }
mkdir -p "$dir"

echo "| method | flight | rows | wall [s] | peak RSS [MB] |"
echo "|---|---|---|---|---|"
for m in $minutes; do
  log="$dir/flight_${m}min.csv"
  if [[ ! -s "$log" ]]; then
    sed "s/^  duration_s: .*/  duration_s: $((m * 60))/" "$root/configs/scenarios/flight.yaml" \
      > "$dir/flight_${m}min.yaml"
    "$coaxid" simulate --config="$root/configs/glmav.yaml" --scenario="$dir/flight_${m}min.yaml" \
      --out="$log" >&2
  fi
  rows=$(grep -vc '^#' "$log")
  for method in $methods; do
    extra=()
    logs="$log,$root/data/glmav/balance.csv"
    what="$m min + balance"
    command=(identify --method="$method")
    if [[ "$method" == ekf ]]; then
      extra=(--smoother)
      logs="$log"
      what="$m min"
    elif [[ "$method" == discover ]]; then
      command=(discover)
      logs="$log"
      what="$m min"
    fi
    out="$dir/${method}_${m}min"
    /usr/bin/time -v -o "$dir/${method}_${m}min.time" "$coaxid" "${command[@]}" \
      "${extra[@]}" --logs="$logs" --config="$root/configs/glmav.yaml" \
      --out="$out" > /dev/null 2> "$dir/${method}_${m}min.err" ||
      { echo "long_flight.sh: $method on $m min failed: see $dir/${method}_${m}min.err" >&2; exit 1; }
    wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, p, ":"); s = 0;
                 for (i = 1; i <= n; ++i) s = s * 60 + p[i]; printf "%.1f", s}' "$dir/${method}_${m}min.time")
    rss=$(awk '/Maximum resident set size/ {printf "%.0f", $NF / 1024}' "$dir/${method}_${m}min.time")
    echo "| $method | $what | $((rows - 1)) | $wall | $rss |"
  done
done
