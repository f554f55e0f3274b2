#!/usr/bin/env bash
# A 60:1 gearmotor sampled at 100 Hz (3840 encoder counts per output turn over a 10 ms window),
# its friction on the motor shaft a Coulomb offset of 1.5 V of drive (Tc 0.00784 N m) with
# breakaway at 1.7 V (Ts 0.00889 N m) and a little viscous drag, described from its datasheet
# without friction; the gear ratio stated once, in the model's [measurement].
#  - mcg-fit friction: Coulomb and viscous within two of their standard errors (the larger of
#    the windows' OLS and the jackknife over the holds), the breakaway's covering the truth;
#  - mcg-fit gap: friction_levels is the diagnosis, with shrink >= 60 % on the held-out run and
#    Tc, c1 and the breakaway excess within two standard errors. The breakaway is profiled on
#    the exact stick-slip after the fit on the regularised one: before, the fit left it 15 %
#    high (0.001209 +- 1.1e-05 N m against 0.00105).
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sim mcg-fit

# motor_ini TS TC C1: the gearmotor (motor shaft values), its friction in N m
motor_ini() {
  printf '[motor]\nR_ohm = 2.2\nL_H = 0.0025\nKt_Nm_A = 0.0115\nKe_V_s_rad = 0.0115\nJ_kg_m2 = 5e-6\n'
  printf 'Ts_Nm = %s\nTc_Nm = %s\nvisc1_Nm_s_rad = %s\n' "$1" "$2" "$3"
  printf 'visc2_Nm_s2_rad2 = 0\nvisc3_Nm_s3_rad3 = 0\n'
  printf '[drive]\nsupply_V = 12\n[measurement]\ngear_ratio = 60\n'
}
motor_ini 0.00889 0.00784 1e-6 >"$work/truth.ini"
motor_ini 0 0 0 >"$work/given.ini"

# program SEGMENTS: the inputs at 100 Hz (segments in lib.sh)
program() { segments 0.01 "$1"; }
# measure SEED: the truth's run of the inputs on stdin, the output shaft's rpm by the encoder
measure() {
  mcg-sim --config "$work/truth.ini" --encoder --window 0.01 --counts-per-rev 3840 --seed "$1" |
    awk -F, -v OFS=, '/^#/ { print; next } { print $1, $2, $3, $4, $6 }'
}
program "hold 0 0.5;hold 3 2;hold 6 2;hold 9 2;hold 12 2;hold 0 2;hold -3 2;hold -6 2;hold -9 2;hold 0 2;\
ramp 0 3 10;hold 0 1;ramp 0 -3 10;hold 0 1" | measure 1 >"$work/train.csv"
program "hold 0 0.5;hold 4 2;hold 8 2;hold 11 2;hold 0 2;hold -4 2;hold -8 2;hold -11 2;hold 0 2;\
ramp 0 2.5 8;hold 0 1;ramp 0 -2.5 8;hold 0 1" | measure 2 >"$work/validate.csv"

# within NAME VALUE SE TRUTH: |VALUE - TRUTH| <= 2 SE, plus the rounding of a value printed to 4
# significant digits
within() {
  if awk -v v="$2" -v s="$3" -v w="$4" \
    'BEGIN { d = v - w; if (d < 0) d = -d; r = 5e-4 * (w < 0 ? -w : w); exit !(s > 0 && d <= 2 * s + r) }'; then
    pass
  else
    fail "$1 = $2 +- $3, truth $4: not within two standard errors"
  fi
}

mcg-fit friction --config "$work/given.ini" --order 1 "$work/train.csv" "$work/validate.csv" \
  >"$work/friction.ini"
value() { awk -v k="$1" '$1 == k && $2 == "=" { print $3; exit }' "$work/friction.ini"; }
se() { awk -v k="$1" '$1 == k && $2 == "=" { print $6; exit }' "$work/friction.ini"; }
within "friction: Tc_Nm" "$(value Tc_Nm)" "$(se Tc_Nm)" 0.00784
within "friction: visc1_Nm_s_rad" "$(value visc1_Nm_s_rad)" "$(se visc1_Nm_s_rad)" 1e-6
within "friction: Ts_Nm" "$(value Ts_Nm)" "$(se Ts_Nm)" 0.00889
echo "friction: Tc $(value Tc_Nm) +- $(se Tc_Nm), c1 $(value visc1_Nm_s_rad) +- $(se visc1_Nm_s_rad)," \
  "Ts $(value Ts_Nm) +- $(se Ts_Nm)"

mcg-fit gap --budget 900 --config "$work/given.ini" \
  --train "$work/train.csv" --validate "$work/validate.csv" \
  >"$work/gap.csv" 2>"$work/gap.err" || fail "gap: exit $?: $(tail -1 "$work/gap.err")"
row=$(grep -v '^#' "$work/gap.csv" | sed -n 2p)
echo "gap: $(cut -d, -f1,4,15 <<<"$row")"
if [[ "$(cut -d, -f1 <<<"$row")" != friction_levels ]]; then
  fail "gap: diagnosis $(cut -d, -f1 <<<"$row"), expected friction_levels"
else
  pass
  shrink=$(cut -d, -f4 <<<"$row")
  awk -v s="$shrink" 'BEGIN { exit !(s >= 60) }' && pass || fail "gap: shrink $shrink % < 60 %"
  param() { grep -o "friction_levels.$1=[^ ,]*" <<<"$row" | cut -d= -f2; }
  for p in "Tc_Nm 0.00784" "c1_Nm_s_rad 1e-6" "Ts_excess_Nm 0.00105"; do
    set -- $p
    v=$(param "$1")
    within "gap: friction_levels.$1" "${v%%+-*}" "${v##*+-}" "$2"
  done
fi
finish gap_gearmotor
