#!/usr/bin/env bash
# Builds the tools and benchmarks in one build type (Release unless BUILD_TYPE says otherwise)
# and prints the README's benchmark table as markdown rows, each saying whether its figure is a
# whole process (the tool as users run it, files in and out, median wall time of several runs)
# or in-library (a benchmark of the library call), with the goal and whether it is met. The
# raw output of the in-library benchmarks follows the table.
# Usage: bench.sh [SOAK_SECONDS]   (default 600: the 10-minute soak; 0 skips it)
# BUILD_TYPE (Release), BENCH_BUILD_DIR (build-bench), BENCH_NO_BUILD=1: see below.
# ROWS=design,sim limits the rows (names: csv sim sim_stream sim_scipy bode fit gap design firmware soak console cli_battery, and those
# of the scripts in scripts/bench.d/); run it on an idle machine, it measures wall time.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
soak=${1:-600}
build_type=${BUILD_TYPE:-Release}
build="${BENCH_BUILD_DIR:-$root/build-bench}"
# BENCH_NO_BUILD=1 measures an existing build as it is (its type must be BUILD_TYPE).
if [[ -z ${BENCH_NO_BUILD:-} ]]; then
  BUILD_DIR="$build" BUILD_TYPE="$build_type" "$root/scripts/build.sh" -DMCG_BUILD_TESTS=OFF >/dev/null
fi
built_type=$(awk -F= '/^CMAKE_BUILD_TYPE:/ {print $2}' "$build/CMakeCache.txt")
[[ $built_type == "$build_type" ]] || { echo "bench.sh: $build is a '$built_type' build, not $build_type" >&2; exit 1; }
tools="$build/src/tools"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
raw="$work/raw.txt"
: >"$raw"

wanted() { [[ -z ${ROWS:-} || ",$ROWS," == *",$1,"* ]]; }

# row WHAT KIND GOAL MEASURED MET: one markdown row; KIND is whole-process or in-library,
# MET is yes or "missed (plan)".
rows=()
row() { rows+=("| $1 | $2 | $3 | $4 | $5 |"); }

# wall_ms RUNS CMD: median wall time of RUNS runs of the shell command CMD, in ms.
wall_ms() {
  local runs=$1 cmd=$2 i t0 t1
  for ((i = 0; i < runs; i++)); do
    t0=$(date +%s%N)
    bash -c "$cmd" >/dev/null
    t1=$(date +%s%N)
    echo $(((t1 - t0) / 1000))
  done | sort -n | awk '{v[NR] = $1} END {printf "%.1f", v[int((NR + 1) / 2)] / 1000}'
}

# met VALUE OP LIMIT: "yes" or "missed".
met() { awk -v v="$1" -v l="$3" -v op="$2" 'BEGIN {ok = op == "<=" ? v <= l : v >= l; print ok ? "yes" : "missed"}'; }

export PATH="$tools:$PATH"

if wanted csv; then
  "$build/bench/bench_csv" | tee -a "$raw" >"$work/csv.txt"
  # Google Benchmark's bytes_per_second counter, e.g. 410.2Mi/s, in MB/s.
  mbs() {
    awk -v n="$1" '$1 ~ n {for (i = 1; i <= NF; i++) if ($i ~ /bytes_per_second=/) {v = $i; sub(/.*=/, "", v)
      f = v + 0; u = v; sub(/^[0-9.]+/, "", u); m = u ~ /^Gi/ ? 1073.741824 : u ~ /^G/ ? 1000 : u ~ /^Mi/ ? 1.048576 : u ~ /^M/ ? 1 : u ~ /^ki/ ? 0.001024 : 0.001
      printf "%.0f", f * m; exit}}' "$work/csv.txt"
  }
  parse=$(mbs BM_CsvParse)
  write=$(mbs BM_CsvWrite)
  ok=missed
  [[ $(met "${parse:-0}" ">=" 100) == yes && $(met "${write:-0}" ">=" 100) == yes ]] && ok=yes
  row "CSV parse / write, one core (\`bench_csv\`)" in-library ">= 100 MB/s" "$parse MB/s / $write MB/s" "$ok"
fi

if wanted sim; then
  # 60 s of the coupled rig at 1 ms: the excitation as a file, mcg-sim reading and writing CSV.
  mcg-sweep step --column v --level 12 --at 0.5 --duration 60 >"$work/step60.csv"
  ms=$(wall_ms 5 "mcg-sim < '$work/step60.csv' > '$work/sim60.csv'")
  x=$(awk -v ms="$ms" 'BEGIN {printf "%.0f", 60000 / ms}')
  row "\`mcg-sim\` < 60 s input CSV > output CSV, open loop, 1 ms" whole-process ">= 1000x real time" \
    "${ms} ms = ${x}x" "$(met "$x" ">=" 1000)"
  "$build/bench/bench_sim" | tee -a "$raw" >/dev/null
fi

if wanted bode; then
  # One million samples: 1000 s of chirp response simulated once, then mcg-sweep bode on the file.
  mcg-sweep chirp --bias 6 --amp 2 --f0 0.5 --f1 200 --spacing log --duration 1000 --clutch 2 | mcg-sim >"$work/chirp.csv"
  ms=$(wall_ms 3 "mcg-sweep bode --in v --out omega < '$work/chirp.csv'")
  row "\`mcg-sweep bode\` on one million samples, CSV in and out" whole-process "< 500 ms" "$ms ms" \
    "$(met "$ms" "<=" 500)"
  "$build/bench/bench_bode" | tee -a "$raw" >/dev/null
fi

if wanted fit; then "$build/bench/bench_fit" | tee -a "$raw" >/dev/null; fi
if wanted gap; then
  "$build/bench/bench_gap" | tee -a "$raw" >/dev/null
  "$build/bench/bench_gap_null" | tee -a "$raw" >/dev/null
fi

if wanted design; then
  plant='0.0146/((s/60+1)(s/850+1)(s/1800+1))'
  for c in "p --pm 55 --plant '$plant'" \
           "pi --pm 50 --zero 500 --dt 0.001 --plant '$plant' --plant-units loop" \
           "lag --pm 50 --k-dc 2000 --plant '$plant'" \
           "tune --plant '$plant'" \
           "tune" \
           "margins --plant '$plant' --controller '4658(s/500+1)/s'" \
           "step --plant '$plant' --controller '4658(s/500+1)/s'" \
           "rlocus" \
           "bode"; do
    ms=$(wall_ms 7 "mcg-design $c")
    row "\`mcg-design $c\`" whole-process "<= 50 ms" "$ms ms" "$(met "$ms" "<=" 50)"
  done
  "$build/bench/bench_design" 2>/dev/null | tee -a "$raw" >"$work/design.txt"
  for name in p/report-third-order lag/third-order tune/pi-third-order tune/pi-zoh-loop rlocus/zoh-loop step/report-pi; do
    ms=$(awk -v n="$name" '$1 == n {print $2; exit}' "$work/design.txt")
    row "\`mcg-design\` $name, the library call (\`bench_design\`)" in-library "<= 20 ms" "$ms ms" "$(met "${ms:-1e9}" "<=" 20)"
  done
fi

if wanted firmware; then
  echo "== firmware: machine cycles of the 1 ms update in s51 at 12 MHz" >>"$raw"
  "$root/firmware/bench/bench-cycles.sh" "$build/firmware-images" | tee -a "$raw" >/dev/null
fi

# Further rows: each scripts/bench.d/*.sh is sourced here with row, wall_ms, met, wanted,
# $work, $build and the tools on PATH.
for extra in "$root"/scripts/bench.d/*.sh; do
  [[ -e $extra ]] || continue
  # shellcheck source=/dev/null
  source "$extra"
done

if wanted soak && ((soak > 0)); then
  echo "== serial soak: $soak s of streaming from the emulated board" >>"$raw"
  "$build/bench/bench_serial_soak" --seconds "$soak" | tee -a "$raw" >/dev/null
fi

echo "Measured in a $build_type build on $(nproc) cores, $(date -u +%Y-%m-%d)."
echo
echo "| what | figure | goal | measured | goal met |"
echo "|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
echo
echo "In-library benchmarks (raw):"
cat "$raw"
