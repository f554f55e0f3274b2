#!/usr/bin/env bash
# The lab loop on a board in one go: the board plays an identification input itself (a PRBS or a
# chirp on the duty, about 45 % +- 10 %, clutch engaged, relay open), captured from its first tick;
# mcg-fit tf identifies a plant from the capture as it is (time domain, its units from the
# capture's metadata); mcg-design designs a PI on it for the stated phase margin; the PI is loaded
# and stepped from 420 to 520 rpm on the board; the board's rise time (10-90 %), overshoot and
# settling time (2 %) are reported against what mcg-design predicts for that PI on that plant, as
# the board's speed estimator would read it, beside the design's margins, with plots.
# Usage: identify-design-verify.sh PORT PM_DEG OUT_DIR [prbs|chirp]
#   e.g. mcg-sim --board ./ttyMCG --speed 4 &
#        scripts/lab/identify-design-verify.sh ./ttyMCG 50 out
# Writes in OUT_DIR: excite.csv (the capture), plant.ini, pi.ini, predicted.ini ([step] of the
# design), closed.csv (the board's step, with the predicted rpm beside it), report.ini (printed),
# excite.png and closed.png. Exits 1 on a failed step, 2 on a usage error.
set -euo pipefail
usage() { echo "usage: identify-design-verify.sh PORT PM_DEG OUT_DIR [prbs|chirp]" >&2; exit 2; }
[ $# -ge 3 ] && [ $# -le 4 ] || usage
port=$1
pm=$2
out=$3
kind=${4:-prbs}
S() { mcg-serial -p "$port" "$@"; }
mkdir -p "$out"

# The operating point: open loop at 45 % duty, settled before the excitation starts.
S set mode open > /dev/null
S set clutch 2
S set load 0
S set duty 45
case $kind in
  prbs) # order 7, 8 ms a bit: one period of 1.016 s, bits from 8 ms to 56 ms long
    S set exc_kind prbs
    S set exc_order 7
    S set exc_div 8
    seconds=1.016 ;;
  chirp) # 0.5 to 20 Hz over 4 s, a level every tick
    S set exc_kind chirp
    S set exc_f0 0.5
    S set exc_f1 20
    S set exc_sweep 4
    S set exc_div 1
    seconds=4 ;;
  *) usage ;;
esac
S set exc_amp 100
S set exc_offset 450
S set exc_periods 1
sleep 1
S stream --seconds "$seconds" --then excite > "$out/excite.csv"

# Identify and design: the capture's units travel into the plant and the design converts them.
mcg-fit tf --poles 2 "$out/excite.csv" > "$out/plant.ini"
mcg-design pi --pm "$pm" --zero 500 --config "$out/plant.ini" --dt 0.001 > "$out/pi.ini"
mcg-design step --config "$out/pi.ini" --metrics > "$out/predicted.ini"
mcg-design step --config "$out/pi.ini" --t-end 1 > "$out/predicted.csv"

# The closed loop on the board: 420 rpm held, then a step to 520 rpm at t = 1 s.
S load "$out/pi.ini" > /dev/null
S set rpm_cmd 420
S set mode pi
sleep 1.5
printf 't,stream,mode,rpm_cmd\n0,1,2,420\n1,1,2,520\n' > "$out/step.csv"
S send "$out/step.csv" > /dev/null
S stream --seconds 2 --then play > "$out/board-step.csv"
S set mode open

# The board's rpm is its speed estimator's: the counts over a window ending at each row. The
# prediction is read the same way, so that both are measured alike: the design's step y (1 ms rows)
# averaged over that window (trapezoids) at the board's rows, 420 + 100 mean y(t - 1 - window, t - 1].
# Read at once, the design's step rises faster than the board can show (16 ms: about 7 % of a 25 ms
# rise); mcg-design's own figures are reported beside.
window=$(sed -n 's/^# rpm_estimator: counts over \([0-9.eE+-]*\) s window.*/\1/p' "$out/board-step.csv")
[ -n "$window" ] || { echo "identify-design-verify: the capture states no rpm_estimator window" >&2; exit 1; }
awk -F, -v w="$window" 'FNR == NR { if ($0 !~ /^#/ && $1 != "t") { t[n] = $1; y[n++] = $3 }; next }
  function yat(j) { return j < 0 ? 0 : y[j] }
  function ybar(s,  dt, k, i, j, sum) {
    dt = t[1] - t[0]; k = int(w / dt + 0.5); i = int(s / dt + 0.5)
    if (i >= n) return "nan"
    sum = (yat(i - k) + yat(i)) / 2
    for (j = i - k + 1; j < i; j++) sum += yat(j)
    return sum / k }
  /^#/ { print; next }
  !h { h = 1; print $0 ",rpm_predicted"; next }
  { p = 420; if ($1 >= 1) { p = ybar($1 - 1); if (p != "nan") p = 420 + 100 * p }; print $0 "," p }' \
  "$out/predicted.csv" "$out/board-step.csv" > "$out/closed.csv"

# Rise (10-90 %, crossings interpolated between rows), overshoot and settling (last time outside
# +-2 % of the step) of a column of closed.csv after the step: the board's rpm and the prediction.
metrics() {
  grep -v '^#' "$out/closed.csv" | awk -F, -v c="$1" '
  NR == 1 { for (i = 1; i <= NF; i++) if ($i == c) k = i; next }
  $1 >= 1 && $k != "nan" {
    if (!a && $k >= 430) a = pt + (430 - py) / ($k - py) * ($1 - pt)
    if (!b && $k >= 510) b = pt + (510 - py) / ($k - py) * ($1 - pt)
    if ($k > m) m = $k
    if ($k < 518 || $k > 522) s = $1
    pt = $1; py = $k } END { printf "%.6g %.6g %.6g", b - a, m - 520, s - 1 }'
}
read -r rise over settle <<< "$(metrics rpm)"
read -r p_rise p_over p_settle <<< "$(metrics rpm_predicted)"
value() { awk -F' *= *' -v k="$1" '$1 == k { split($2, v, " *;"); print v[1] + 0; exit }' "$2"; }
d_rise=$(value rise_time_s "$out/predicted.ini")
d_over=$(value overshoot_pct "$out/predicted.ini")
d_settle=$(value settling_time_s "$out/predicted.ini")
{
  echo "[report]"
  echo "excitation = $(sed -n 's/^# excitation: //p' "$out/excite.csv")"
  echo "plant = $(value fit_percent "$out/plant.ini")  ; fit %, $(sed -n 's/^maps = //p' "$out/plant.ini" | head -1)"
  echo "pm_deg = $(value pm_deg "$out/pi.ini")  ; the design's phase margin"
  echo "gm_db = $(value gm_db "$out/pi.ini")  ; the design's gain margin"
  echo "rise_time_s = $rise  ; the board; predicted $p_rise"
  echo "overshoot_pct = $over  ; the board; predicted $p_over"
  echo "settling_time_s = $settle  ; the board (2 %, 4 ms rows); predicted $p_settle"
  echo "predicted_rise_time_s = $p_rise  ; the design's step through the ${window} s window;" \
    "mcg-design: $d_rise"
  echo "predicted_overshoot_pct = $p_over  ; the same; mcg-design: $d_over"
  echo "predicted_settling_time_s = $p_settle  ; the same; mcg-design: $d_settle"
  awk -v m="$rise" -v p="$p_rise" 'BEGIN { printf "rise_ratio = %.4g  ; board / predicted\n", m / p }'
} > "$out/report.ini"

mcg-plot-gnuplot -y rpm --title "board-played $kind: the capture identified" -o "$out/excite.png" \
  < "$out/excite.csv"
mcg-plot-gnuplot -y rpm,rpm_predicted,rpm_cmd --title "PI for $pm deg: the board against the design" \
  -o "$out/closed.png" < "$out/closed.csv"
cat "$out/report.ini"
