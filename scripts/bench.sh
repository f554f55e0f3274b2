#!/usr/bin/env bash
# Builds the benchmarks (Release) and prints their figures: CSV throughput, simulation speed,
# bode on a million samples, the grey-box fit, the gap diagnosis, every mcg-design command,
# the firmware's 1 ms update in machine cycles (s51), and the serial soak.
# Usage: bench.sh [SOAK_SECONDS]   (default 600: the 10-minute soak; give less to try it)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
soak=${1:-600}
build="$root/build-bench"
BUILD_DIR="$build" BUILD_TYPE=Release "$root/scripts/build.sh" -DMCG_BUILD_TESTS=OFF >/dev/null
for b in bench_csv bench_sim bench_bode bench_fit bench_design bench_gap; do
  echo "== $b"
  "$build/bench/$b"
done
echo "== firmware: machine cycles of the 1 ms update in s51 at 12 MHz"
"$root/firmware/bench/bench-cycles.sh" "$build/firmware-images"
echo "== serial soak: $soak s of streaming from the emulated board"
"$build/bench/bench_serial_soak" --seconds "$soak"
