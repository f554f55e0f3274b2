#!/usr/bin/env bash
# The hostile-input battery, whole-process: mcg-sim reading from a pipe (1) a line of 1 GB
# without a newline, (2) a header of 10^6 columns, (3) 10^5 metadata lines before a short run.
# Each is run once under /usr/bin/time -v (only mcg-sim is measured, not the generator); prints
# "NAME: T s wall, M MiB peak, exit E, STDERR" per case. (1) and (2) are refused by the reader's
# limits (mcg-csv(5), LIMITS), (3) is read and simulated.
# Usage: bench_cli_battery.sh TOOLS_DIR
set -euo pipefail
tools=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# measure NAME GENERATOR: GENERATOR's output piped into mcg-sim under /usr/bin/time -v.
measure() {
  local name=$1 gen=$2 rc=0
  bash -c "$gen" | /usr/bin/time -v -o "$work/time" "$tools/mcg-sim" >/dev/null 2>"$work/err" || rc=$?
  local wall kib
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {
    n = split($2, p, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + p[i]; print s }' "$work/time")
  kib=$(awk -F': ' '/Maximum resident set size/ { print $2 }' "$work/time")
  echo "$name: $wall s wall, $((kib / 1024)) MiB peak, exit $rc, $(head -c 200 "$work/err" | head -1)"
}

measure "line of 1 GB without a newline" "head -c 1000000000 /dev/zero | tr '\\000' x"
measure "header of 10^6 columns" \
  "awk 'BEGIN { for (i = 0; i < 1000000; i++) printf \"%sc%d\", i ? \",\" : \"\", i; print \"\" }'"
measure "10^5 metadata lines" "awk 'BEGIN { for (i = 0; i < 100000; i++) printf \"# note_%d: %d\\n\", i, i
  print \"t,v\"; for (k = 0; k <= 1000; k++) printf \"%g,8\\n\", k * 0.001 }'"
