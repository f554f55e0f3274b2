#!/usr/bin/env bash
# Coverage-guided fuzzing of mcg's parsers (tests/fuzz): builds the harnesses with clang 14,
# libFuzzer, ASan and UBSan in build-fuzz/ and runs each for SECONDS (default 600), at most
# JOBS at a time (default 2), under nice. New inputs go to build-fuzz/corpus/NAME (seeded from
# tests/fuzz/corpus/NAME); a crash leaves its input in build-fuzz/findings/NAME/ and fails.
# An input that runs longer than TIMEOUT s (default 20, wall clock: raise it on a loaded machine)
# stops its harness as a finding; one over 10 s is kept as slow-unit-* and counted apart.
# Usage: scripts/fuzz.sh [SECONDS] [NAME...]   (names: csv ini_model tf frames firmware serial_inputs margins
#   capture_meta controller_ini bode_meta excitation csv_roundtrip c2d)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-600}
shift || true
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(csv ini_model tf frames firmware serial_inputs margins capture_meta controller_ini
  bode_meta excitation csv_roundtrip c2d)
jobs=${JOBS:-2}
timeout=${TIMEOUT:-20}
build=${FUZZ_BUILD_DIR:-$root/build-fuzz}
"$root/scripts/install-deps.sh" --fuzz
CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$build" -DMCG_FUZZ=ON -DMCG_BUILD_BENCH=OFF >/dev/null
targets=()
for n in "${names[@]}"; do targets+=("fuzz_$n"); done
cmake --build "$build" -j "$(nproc)" --target "${targets[@]}"

run_one() {
  local n=$1 corpus=$build/corpus/$1 findings=$build/findings/$1 rc=0
  mkdir -p "$corpus" "$findings"
  nice -n 19 "$build/tests/fuzz/fuzz_$n" -max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$findings/" "$corpus" "$root/tests/fuzz/corpus/$n" \
    > "$build/fuzz_$n.log" 2>&1 || rc=$?
  local execs cov corp
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/fuzz_$n.log" | grep -o '[0-9]*$' || echo '?')
  cov=$(grep -o 'cov: [0-9]*' "$build/fuzz_$n.log" | tail -1 | grep -o '[0-9]*' || echo '?')
  corp=$(grep -o 'corp: [0-9]*' "$build/fuzz_$n.log" | tail -1 | grep -o '[0-9]*' || echo '?')
  local rate='?'
  [[ $execs == [0-9]* ]] && rate=$((execs / seconds))
  local slow found
  slow=$(find "$findings" -name 'slow-unit-*' | wc -l)
  found=$(find "$findings" -type f ! -name 'slow-unit-*' | wc -l)
  echo "fuzz_$n: ${seconds} s, $execs executions ($rate/s), coverage $cov edges," \
    "corpus $corp inputs, exit $rc ($found findings, $slow slow units)"
  return $rc
}

status=0
pids=()
for n in "${names[@]}"; do
  run_one "$n" & pids+=($!)
  if [ ${#pids[@]} -ge "$jobs" ]; then
    wait "${pids[0]}" || status=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
