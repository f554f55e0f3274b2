# Rows for the hostile-input battery (bench/bench_cli_battery.sh): peak memory and wall time of
# mcg-sim on a 1 GB line without a newline, a header of 10^6 columns and 10^5 metadata lines.
# Sourced by scripts/bench.sh (row, met, wanted, $work, $raw).
if wanted cli_battery; then
  "$root/bench/bench_cli_battery.sh" "$build/src/tools" | tee -a "$raw" >"$work/cli_battery.txt"
  while IFS= read -r line; do
    name=${line%%:*}
    s=$(sed -n 's/.*: \([0-9.]*\) s wall.*/\1/p' <<<"$line")
    mib=$(sed -n 's/.* \([0-9]*\) MiB peak.*/\1/p' <<<"$line")
    verdict=$(sed -n 's/.*MiB peak, \(exit [0-9]*\).*/\1/p' <<<"$line")
    ok=$(awk -v s="${s:-1e9}" -v m="${mib:-1e9}" 'BEGIN { print (s <= 5 && m <= 64) ? "yes" : "missed" }')
    row "\`mcg-sim\` on a $name, wall time and peak memory" whole-process "<= 5 s, <= 64 MiB" \
      "$s s, $mib MiB ($verdict)" "$ok"
  done <"$work/cli_battery.txt"
fi
