#!/usr/bin/env bash
# A real small gearmotor behind a PWM driver that coasts (tests/data/real/undcmotor, MIT): its
# measured static curve rises far faster than the duty at low duty, which no braking drive can
# give (its steady speed is affine in the duty above the breakaway).
#  - the best straight line through the 94 moving points misses them by more than 100 deg/s RMS;
#  - mcg-sim with the set's model (from the curve, PROVENANCE.md) and pwm_coast coast = 1 lands
#    within 4 deg/s RMS of them; the same model with a braking drive misses by more than 100;
#  - the points measured at rest (|u| <= 0.315 V) stay within one 6.43 deg/s count of 0.
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
src=$(cd "$2" && pwd)
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sim
set_dir="$src/tests/data/real/undcmotor"

awk -F, 'NR > 1 { print $2 }' "$set_dir/static_curve.csv" >"$work/measured"
# steady EFFECT...: the steady speed (deg/s) at each u of the curve, 4 s a level (10 time constants)
steady() {
  awk -F, 'BEGIN { print "t,v,clutch,r_load" }
    NR > 1 { for (k = 0; k < 400; ++k) { printf "%.2f,%s,0,inf\n", t, $1; t += 0.01 } }' \
    "$set_dir/static_curve.csv" | mcg-sim --config "$set_dir/model.ini" "$@" |
    awk -F, '/^#/ || $1 == "t" { next } { if (++r % 400 == 0) print $6 * 6 }'
}
steady --effect pwm_coast:coast=1 >"$work/coast"
steady >"$work/braking"

# rms FILE: RMS of measured - FILE over the moving points
rms() {
  paste -d' ' "$work/measured" "$1" |
    awk '$1 != 0 { n++; s += ($1 - $2)^2 } END { printf "%.2f", sqrt(s / n) }'
}
# the best straight line |y| = a |u| + b through the moving points, its RMS miss
line=$(awk -F, 'NR > 1 && $2 != 0 {
    u = $1 < 0 ? -$1 : $1; y = $2 < 0 ? -$2 : $2; U[++n] = u; Y[n] = y
    su += u; sy += y; suu += u * u; suy += u * y }
  END { a = (n * suy - su * sy) / (n * suu - su * su); b = (sy - a * su) / n
    for (k = 1; k <= n; ++k) s += (Y[k] - a * U[k] - b)^2
    printf "%.1f", sqrt(s / n) }' "$set_dir/static_curve.csv")
coast=$(rms "$work/coast")
braking=$(rms "$work/braking")
echo "static curve RMS: best line $line, coasting driver $coast, braking driver $braking deg/s"
above() { awk -v x="$1" -v y="$2" 'BEGIN { exit !(x > y) }'; }
check "the best line misses the curve by more than 100 deg/s ($line)" above "$line" 100
check "the coasting driver within 4 deg/s ($coast)" above 4 "$coast"
check "the braking driver off by more than 100 deg/s ($braking)" above "$braking" 100
at_rest=$(paste -d' ' "$work/measured" "$work/coast" |
  awk '$1 == 0 { d = $2 < 0 ? -$2 : $2; if (d > m) m = d } END { printf "%.2f", m }')
check "the points at rest stay within one count of 0 ($at_rest deg/s)" above 6.43 "$at_rest"
finish undcmotor
