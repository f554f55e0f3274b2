#!/usr/bin/env bash
# Runs a speed-step profile on the board (or the emulated one: mcg-sim --board PATH) under a
# designed controller, captures the live stream, simulates the same profile on the model with
# the same controller, and plots measured against simulated.
# Usage: capture-compare.sh PORT CONTROLLER.ini OUT_DIR
#
# The capture is the model's input as it stands: from rest, the sequence turns the stream on,
# switches to the controller's mode and plays the speed command, so t = 0 is the same instant
# on the board and in the model, and every row carries its rpm_cmd, clutch and r_load.
set -euo pipefail
port=$1
controller=$2
out=$3
mkdir -p "$out"
S() { mcg-serial -p "$port" "$@"; }
# The controller's registers, then back to open loop at rest, clutch engaged, relay open.
S load "$controller" > "$out/loaded.ini"
case "$(S get mode)" in
  p) mode=1 ;;
  pi) mode=2 ;;
  pid) mode=3 ;;
  *) echo "capture-compare.sh: $controller loads no closed-loop mode" >&2; exit 1 ;;
esac
S set mode open
S set duty 0
S set clutch 2
S set load 0
S set rpm_cmd 300
sleep 2
printf 't,stream,mode,rpm_cmd\n0,1,%s,300\n1.2,1,%s,420\n2.2,1,%s,520\n' "$mode" "$mode" "$mode" > "$out/profile.csv"
S send "$out/profile.csv" > /dev/null
S stream --seconds 3.2 --then play > "$out/measured.csv"
S set mode open
S set duty 0
# The model runs the same controller on the capture's rpm_cmd, clutch and r_load.
mcg-sim --config "$controller" --encoder --window 0.016 < "$out/measured.csv" > "$out/simulated.csv"
mcg-plot-gnuplot -y rpm --overlay "$out/simulated.csv" --title "board (solid) and model (dashed)" \
  -o "$out/compare.png" "$out/measured.csv"
# The figure: rpm of both tables, row by row (the same t), where the board measured it.
paste -d, <(grep -v '^#' "$out/measured.csv" | cut -d, -f2) <(grep -v '^#' "$out/simulated.csv" | cut -d, -f2) |
  awk -F, 'NR > 1 && $1 != "nan" { d = $1 - $2; s += d * d; n++ } END { printf "board vs model: rpm RMS difference %.2f rpm over %d samples\n", sqrt(s / n), n }'
