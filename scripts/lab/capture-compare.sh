#!/usr/bin/env bash
# Runs a speed-step profile on the board (or the emulated one: mcg-sim --board PATH) under a
# designed controller, captures the live stream, simulates the same profile on the model with
# the same controller, and plots measured against simulated.
# Usage: capture-compare.sh PORT CONTROLLER.ini OUT_DIR
set -euo pipefail
port=$1
controller=$2
out=$3
mkdir -p "$out"
# Engaged, under the controller at 300 rpm for a second; then the profile plays from the
# board's RAM while we stream.
mcg-serial -p "$port" set clutch 2 >/dev/null
mcg-serial -p "$port" set rpm_cmd 300 >/dev/null
mcg-serial -p "$port" load "$controller" >/dev/null
sleep 1
printf 't,rpm_cmd\n0,300\n0.2,420\n1.2,520\n' > "$out/profile.csv"
mcg-serial -p "$port" send "$out/profile.csv" --then play >/dev/null
mcg-serial -p "$port" stream --seconds 2 > "$out/measured.csv"
# The model, driven by the command the board logged (clutch engaged, relay open), after the
# same second at 300 rpm (rows before t = 0, dropped from the output).
awk -F, 'BEGIN { OFS = ","; print "t,rpm_cmd,clutch,r_load"; for (k = 1000; k > 0; k--) print -k * 0.001, 300, 2, "inf" }
  /^#/ { next }
  !h { for (k = 1; k <= NF; k++) col[$k] = k; h = 1; next }
  { c = $col["rpm_cmd"]; if (c == "nan") c = (last == "" ? 300 : last); else last = c; print $col["t"], c, 2, "inf" }' \
  "$out/measured.csv" | mcg-sim --config "$controller" --encoder --window 0.016 \
  | awk -F, '/^#/ || !h { print; if (!/^#/) h = 1; next } $1 >= 0' > "$out/simulated.csv"
mcg-plot-gnuplot -y rpm --overlay "$out/simulated.csv" --title "board (solid) and model (dashed)" \
  -o "$out/compare.png" "$out/measured.csv"
awk -F, '/^#/ { next } !h { for (k = 1; k <= NF; k++) if ($k == "rpm") c = k; h = 1; next } { print $c }' "$out/measured.csv" > "$out/.m"
awk -F, '/^#/ { next } !h { for (k = 1; k <= NF; k++) if ($k == "rpm") c = k; h = 1; next } { print $c }' "$out/simulated.csv" > "$out/.s"
paste -d, "$out/.m" "$out/.s" | awk -F, '$1 != "nan" { d = $1 - $2; s += d * d; n++ } END { printf "board vs model: rpm RMS difference %.2f rpm over %d samples\n", sqrt(s / n), n }'
rm -f "$out/.m" "$out/.s"
