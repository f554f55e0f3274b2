# mcg-plot-gnuplot --live as a lab watches it (bench/bench_plot_live.sh): paced rows at 500 a second
# into `--live -o frame.png --interval 0.5` for PLOT_LIVE_SECONDS (600; 0 skips it): the frame age's
# p99 within the interval + 100 ms, and flat memory (under 1 MiB of growth after the first minute,
# the tool and its gnuplot). Sourced by scripts/bench.sh (row, met, wanted, $work, $raw).
plot_live_s=${PLOT_LIVE_SECONDS:-600}
if wanted plot_live && ((plot_live_s > 0)); then
  "$root/bench/bench_plot_live.sh" "$build/src/tools" "$plot_live_s" | tee -a "$raw" >"$work/plot_live.txt"
  p99=$(sed -n 's/.*frame age median [0-9]* ms, p99 \([0-9]*\) ms.*/\1/p' "$work/plot_live.txt")
  tool_growth=$(sed -n 's/.*(growth after the first minute \(-*[0-9]*\) KiB).*/\1/p' "$work/plot_live.txt")
  gp_growth=$(sed -n 's/.*gnuplot.*(growth \(-*[0-9]*\) KiB).*/\1/p' "$work/plot_live.txt")
  figure=$(sed -n 's/.*: exit [0-9]*, \(.*\)/\1/p' "$work/plot_live.txt")
  ok=$(met "${p99:-1e9}" "<=" 600)
  [[ $(met "${tool_growth:-1e9}" "<=" 1024) == yes && $(met "${gp_growth:-1e9}" "<=" 1024) == yes ]] ||
    ok="missed (memory grew)"
  what="\`mcg-plot-gnuplot --live -o frame.png --interval 0.5\` on rows paced at 500/s for $plot_live_s s"
  row "$what (\`bench/bench_plot_live.sh\`)" \
    whole-process "frame age p99 <= interval + 100 ms, flat memory" "${figure:-not measured}" "$ok"
fi
