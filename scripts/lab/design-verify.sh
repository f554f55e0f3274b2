#!/usr/bin/env bash
# Designs a PI for a phase margin on a plant, verifies it on the nonlinear model quantised like
# the firmware, and plots the step.
# Usage: design-verify.sh PLANT.ini|'PLANT TEXT' PM_DEG OUT_DIR
#   e.g. design-verify.sh '16.557/((s/65+1)*(s/950+1))' 50 out/
set -euo pipefail
plant=$1
pm=$2
out=$3
mkdir -p "$out"
if [ -f "$plant" ]; then src=(--config "$plant"); else src=(--plant "$plant"); fi
mcg-design pi --pm "$pm" --zero 500 "${src[@]}" --loop --dt 0.001 > "$out/pi.ini"
mcg-design margins "${src[@]}" --loop --config "$out/pi.ini" > "$out/margins.ini"
mcg-sweep step --column rpm_cmd --level 420 --at 0.05 --then 520@1 --duration 2 --clutch 2 \
  | mcg-sim --config "$out/pi.ini" > "$out/verify.csv"
mcg-plot-gnuplot -y rpm,rpm_cmd --title "PI for ${pm} deg on the nonlinear model" -o "$out/verify.png" < "$out/verify.csv"
grep -E '^(pm_deg|gm_db|wc_rad_s) *=' "$out/margins.ini" || true
