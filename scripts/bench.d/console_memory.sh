# mcg-serial console's memory over an hour of streaming (bench/bench_console_memory.sh): flat
# means less than 1 MiB of growth after the first minute. CONSOLE_SECONDS (3600) sets the length,
# 0 skips it. Sourced by scripts/bench.sh (row, met, wanted, $work, $raw).
console_s=${CONSOLE_SECONDS:-3600}
if wanted console && ((console_s > 0)); then
  "$root/bench/bench_console_memory.sh" "$build/src/tools" "$console_s" | tee -a "$raw" >"$work/console.txt"
  growth=$(sed -n 's/.*growth after the first minute \(-*[0-9]*\) KiB.*/\1/p' "$work/console.txt")
  lost=$(sed -n 's/.* \([0-9]*\) samples lost.*/\1/p' "$work/console.txt")
  figure=$(sed -n 's/.*VmRSS \([0-9]*\) KiB at 60 s, \([0-9]*\) KiB at the end.*/\1 KiB at 60 s, \2 KiB at the end/p' "$work/console.txt")
  ok=$(met "${growth:-1e9}" "<=" 1024)
  [[ ${lost:-1} == 0 ]] || ok="missed (${lost:-?} samples lost)"
  row "\`mcg-serial console\` against the emulated board for $console_s s, recording the stream, rpm_cmd written through it every 5 s: resident memory" \
    whole-process "flat (< 1 MiB growth after the first minute)" "${figure:-not measured}, ${lost:-?} samples lost" "$ok"
fi
