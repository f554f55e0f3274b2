#!/usr/bin/env bash
# Captures a closed-loop run from the board (or the emulated one, mcg-sim --board PATH),
# replays the logged duty through the model, and plots measured against simulated.
# Usage: capture-compare.sh PORT SECONDS OUT_DIR
set -euo pipefail
port=$1
seconds=$2
out=$3
mkdir -p "$out"
mcg-serial -p "$port" set rpm_cmd 420
mcg-serial -p "$port" stream --seconds "$seconds" > "$out/measured.csv"
# The logged duty is the plant's input; clutch and load as the board's registers say.
clutch=$(mcg-serial -p "$port" get clutch | awk '{print $NF}')
awk -F, -v c="$clutch" 'BEGIN { OFS = "," } /^#/ { print; next } !h { for (k = 1; k <= NF; k++) col[$k] = k; print "t,duty,clutch"; h = 1; next } { print $col["t"], $col["duty"], c }' \
  "$out/measured.csv" | mcg-sim --encoder --open-loop > "$out/simulated.csv"
mcg-plot-gnuplot -y rpm --overlay "$out/simulated.csv" --title "board vs model" -o "$out/compare.png" "$out/measured.csv"
