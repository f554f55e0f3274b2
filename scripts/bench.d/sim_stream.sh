# Rows for mcg-sim as a whole process and as a live filter (bench/bench_sim_stream.sh): the
# closed loop's real-time factor with CSV in and out, the peak memory on 600 s, the latency of a
# row through the pipe at 500 rows/s. Sourced by scripts/bench.sh (row, met, wanted, $work, $raw).
if wanted sim_stream; then
  "$root/bench/bench_sim_stream.sh" "$build/src/tools" | tee -a "$raw" >"$work/sim_stream.txt"
  x=$(sed -n 's/.*s wall (best of 5), \([0-9]*\)x real time.*/\1/p' "$work/sim_stream.txt")
  row "\`mcg-sim\` < 60 s input CSV > output CSV, closed loop under the PI, 1 ms" whole-process \
    ">= 1000x real time" "${x}x" "$(met "${x:-0}" ">=" 1000)"
  mib=$(sed -n 's/.*peak memory \([0-9]*\) MiB.*/\1/p' "$work/sim_stream.txt")
  row "\`mcg-sim\` on 600 s at 1 kHz (600000 rows), peak memory" whole-process "<= 40 MiB" "${mib} MiB" \
    "$(met "${mib:-1e9}" "<=" 40)"
  p99=$(sed -n 's/.*p99 \([0-9.]*\) ms.*/\1/p' "$work/sim_stream.txt")
  row "\`mcg-sim\` as a live filter at 500 rows/s, latency of a row (p99)" whole-process "< 100 ms" \
    "${p99} ms" "$(met "${p99:-1e9}" "<=" 100)"
fi
