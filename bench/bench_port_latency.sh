#!/usr/bin/env bash
# Latency through the port owner while it streams from the emulated board: a client stream's
# first row (the time from starting `mcg-serial stream --samples 16` to its first block) and a
# full `get` (every register), each the median of 5 tries a few seconds apart.
# Usage: bench_port_latency.sh TOOL_DIR. Prints one line:
#   "port latency: first row X s, full get Y s (medians of 5)"
set -u
export PATH="$(cd "$1" && pwd):$PATH"
command -v mcg-serial > /dev/null || { echo "no mcg-serial in $1" >&2; exit 1; }
work=$(mktemp -d)
export XDG_RUNTIME_DIR=$work
trap 'kill $board $owner 2> /dev/null; wait 2> /dev/null; rm -rf "$work"' EXIT
cd "$work" || exit 1
mcg-sim --board ./ttyB 2> board.err &
board=$!
for _ in $(seq 100); do [ -e ./ttyB ] && break; sleep 0.1; done
mcg-serial -p ./ttyB stream --allow-loss > own.csv 2> own.err &
owner=$!
sleep 4
now() { date +%s.%N; }
median() { sort -g | sed -n 3p; }
first=$(for _ in 1 2 3 4 5; do
  t0=$(now)
  if mcg-serial -p ./ttyB stream --samples 16 > client.csv 2> /dev/null; then echo "$(now) - $t0" | bc; else echo inf; fi
  sleep 2.5
done | median)
full=$(for _ in 1 2 3 4 5; do
  t0=$(now)
  if mcg-serial -p ./ttyB get > all.ini 2> /dev/null; then echo "$(now) - $t0" | bc; else echo inf; fi
  sleep 2.5
done | median)
printf 'port latency: first row %.2f s, full get %.2f s (medians of 5)\n' "$first" "$full"
