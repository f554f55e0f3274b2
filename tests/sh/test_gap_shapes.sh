#!/usr/bin/env bash
# Two self-made cases of the shapes a catalog effect may or may not tell apart, on the built-in
# rig (speed by the 2048-count encoder):
#  - friction growing with the load torque (friction_load, mu 0.15) with the generator engaged
#    and its load switched (open, 4 ohm, 1 ohm), speed and current measured: friction_load is
#    the diagnosis with mu within two standard errors of 0.15, not a Kt error;
#  - the Coulomb level withheld (Tc 0) on staircases that drive the motor one way only, speed
#    alone: a Coulomb level, a brush drop and a dead band of the drive are one constant torque
#    there (save where the current reverses), so the verdict says these runs hardly tell them
#    apart and that runs in both directions do; the coasts still favour the Coulomb level, whose
#    breakaway no start from rest sets (it is pinned, not a reason to set friction aside).
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sim mcg-fit

# staircase BASE STEP HOLD CLUTCH LOADED: 3 s at 1 kHz, five levels BASE + k STEP; LOADED 1
# switches the generator's load every 0.4 s
staircase() {
  awk -v b="$1" -v s="$2" -v h="$3" -v cl="$4" -v ld="$5" 'BEGIN {
    print "t,v,clutch,r_load"
    for (n = 0; n <= 3000; ++n) {
      t = n * 0.001; slot = int(t / 0.4) % 3; r = "inf"
      if (ld && slot == 1) r = 4
      if (ld && slot == 2) r = 1
      printf "%.6g,%.6g,%d,%s\n", t, b + s * (int(t / h) % 5), cl, r
    }
  }'
}
# keep COLUMNS: the named columns of mcg-sim's output (metadata kept)
keep() {
  awk -F, -v OFS=, -v want="$1" '/^#/ { print; next }
    !h { n = split(want, w, ","); for (k = 1; k <= NF; ++k) col[$k] = k; h = 1 }
    { line = ""; for (k = 1; k <= n; ++k) line = line (k > 1 ? OFS : "") $(col[w[k]]); print line }'
}

# Friction that grows with the load torque.
staircase 4 3 0.3 2 1 | mcg-sim --effect friction_load:mu=0.15 --encoder --seed 1 |
  keep t,v,clutch,r_load,rpm,i >"$work/load-train.csv"
staircase 4.8 2.4 0.23 2 1 | mcg-sim --effect friction_load:mu=0.15 --encoder --seed 2 |
  keep t,v,clutch,r_load,rpm,i >"$work/load-validate.csv"
mcg-fit gap --budget 300 --format text --train "$work/load-train.csv" --validate "$work/load-validate.csv" \
  >"$work/load.txt" 2>"$work/load.err" || fail "load: exit $?: $(tail -1 "$work/load.err")"
check "load: the diagnosis is friction_load" grep -q '^diagnosis: friction_load$' "$work/load.txt"
mu=$(grep -o 'friction_load.mu=[^ ]*' "$work/load.txt" | head -1 | cut -d= -f2)
check "load: mu ${mu:-missing} within two standard errors of 0.15" awk -v m="${mu%%+-*}" -v s="${mu##*+-}" \
  'BEGIN { d = m - 0.15; if (d < 0) d = -d; exit !(m != "" && s > 0 && s < 0.0075 && d <= 2 * s + 1e-4) }'

# The Coulomb level withheld, one direction only.
printf '[motor]\nTc_Nm = 0\nTs_Nm = 0.003\n' >"$work/no-coulomb.ini"
staircase 2 1.5 0.3 0 0 | mcg-sim --encoder --seed 1 | keep t,v,clutch,r_load,rpm >"$work/oneway-train.csv"
staircase 2.4 1.2 0.23 0 0 | mcg-sim --encoder --seed 2 |
  keep t,v,clutch,r_load,rpm >"$work/oneway-validate.csv"
mcg-fit gap --budget 300 --format text --config "$work/no-coulomb.ini" --train "$work/oneway-train.csv" \
  --validate "$work/oneway-validate.csv" >"$work/oneway.txt" 2>"$work/oneway.err" ||
  fail "one way: exit $?: $(tail -1 "$work/oneway.err")"
diagnosis=$(sed -n 's/^diagnosis: //p' "$work/oneway.txt")
check "one way: the diagnosis ($diagnosis) is the withheld Coulomb level" \
  grep -qx friction_levels <<<"$diagnosis"
check "one way: the breakaway no start from rest sets is pinned, not a reason to set friction aside" \
  grep -q "^  friction_levels .*Ts_excess_Nm pinned at 0" "$work/oneway.txt"
reason=$(sed -n 2p "$work/oneway.txt")
told='hardly tell them apart (runs in both directions, or the current measured, do)'
check "one way: the verdict says these runs hardly tell them apart" grep -q "one way only.*$told" <<<"$reason"
for effect in friction_levels brush_drop hbridge; do
  [[ $diagnosis == "$effect"* ]] && continue
  check "one way: the verdict names $effect beside $diagnosis" grep -q "($effect" <<<"$reason"
done
finish gap_shapes
