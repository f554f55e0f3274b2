#!/usr/bin/env bash
# The lab loop on a board in one go: the board plays an identification input itself (a PRBS or a
# chirp on the duty, about 45 % +- 10 %, clutch engaged, relay open), captured from its first tick;
# mcg-fit tf identifies a plant from the capture as it is (time domain, its units from the
# capture's metadata); mcg-design designs a PI on it for the stated phase margin; the PI is loaded
# and stepped from 420 to 520 rpm on the board; the board's rise time (10-90 %), overshoot and
# settling time (2 %) are reported against what mcg-design predicts for that PI on that plant,
# beside the design's margins, with plots.
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

# The board's step beside the prediction (420 + 100 y(t - 1), y the design's unit step).
awk -F, 'FNR == NR { if ($0 !~ /^#/ && $1 != "t") y[sprintf("%.3f", $1)] = $3; next }
  /^#/ { print; next }
  !h { h = 1; print $0 ",rpm_predicted"; next }
  { k = sprintf("%.3f", $1 - 1); p = $1 < 1 ? 420 : (k in y ? 420 + 100 * y[k] : "nan"); print $0 "," p }' \
  "$out/predicted.csv" "$out/board-step.csv" > "$out/closed.csv"

# Rise (10-90 %, crossings interpolated between rows), overshoot and settling (last time outside
# +-2 % of the step) of the board's rpm after the step.
read -r rise over settle <<< "$(grep -v '^#' "$out/closed.csv" | awk -F, 'NR > 1 && $1 >= 1 && $2 != "nan" {
  if (!a && $2 >= 430) a = pt + (430 - py) / ($2 - py) * ($1 - pt)
  if (!b && $2 >= 510) b = pt + (510 - py) / ($2 - py) * ($1 - pt)
  if ($2 > m) m = $2
  if ($2 < 518 || $2 > 522) s = $1
  pt = $1; py = $2 } END { printf "%.6g %.6g %.6g", b - a, m - 520, s - 1 }')"
value() { awk -F' *= *' -v k="$1" '$1 == k { split($2, v, " *;"); print v[1] + 0; exit }' "$2"; }
p_rise=$(value rise_time_s "$out/predicted.ini")
p_over=$(value overshoot_pct "$out/predicted.ini")
p_settle=$(value settling_time_s "$out/predicted.ini")
{
  echo "[report]"
  echo "excitation = $(sed -n 's/^# excitation: //p' "$out/excite.csv")"
  echo "plant = $(value fit_percent "$out/plant.ini")  ; fit %, $(sed -n 's/^maps = //p' "$out/plant.ini" | head -1)"
  echo "pm_deg = $(value pm_deg "$out/pi.ini")  ; the design's phase margin"
  echo "gm_db = $(value gm_db "$out/pi.ini")  ; the design's gain margin"
  echo "rise_time_s = $rise  ; the board; predicted $p_rise"
  echo "overshoot_pct = $over  ; the board; predicted $p_over"
  echo "settling_time_s = $settle  ; the board (2 %, 4 ms rows); predicted $p_settle"
  awk -v m="$rise" -v p="$p_rise" 'BEGIN { printf "rise_ratio = %.4g  ; board / predicted\n", m / p }'
} > "$out/report.ini"

mcg-plot-gnuplot -y rpm --title "board-played $kind: the capture identified" -o "$out/excite.png" \
  < "$out/excite.csv"
mcg-plot-gnuplot -y rpm,rpm_predicted,rpm_cmd --title "PI for $pm deg: the board against the design" \
  -o "$out/closed.png" < "$out/closed.csv"
cat "$out/report.ini"
