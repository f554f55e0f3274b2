# Latency through the port owner while it streams (bench/bench_port_latency.sh): a client
# stream's first row and a full get. Sourced by scripts/bench.sh (row, met, wanted, $work, $raw).
if wanted port; then
  "$root/bench/bench_port_latency.sh" "$build/src/tools" | tee -a "$raw" > "$work/port.txt"
  first=$(sed -n 's/.*first row \([0-9.a-z]*\) s.*/\1/p' "$work/port.txt")
  full=$(sed -n 's/.*full get \([0-9.a-z]*\) s.*/\1/p' "$work/port.txt")
  row "a client \`mcg-serial stream\` through the port owner while it streams: start to first row (median of 5)" \
    whole-process "<= 0.5 s" "${first:-?} s" "$(met "${first:-1e9}" "<=" 0.5)"
  row "a full \`mcg-serial get\` (every register) through the port owner while it streams (median of 5)" \
    whole-process "<= 0.5 s (the 9600 baud line leaves room for one answer per 0.12 s beside the stream)" \
    "${full:-?} s" "$(met "${full:-1e9}" "<=" 0.5)"
fi
