#!/usr/bin/env bash
# A small 12 V motor (speed only, 2 kHz, 16384 counts/rev) behind a driver with a duty dead band
# of 0.05 (0.6 V at 12 V) AND Coulomb friction worth 0.6 V of drive (breakaway 0.85 V), described
# from its datasheet without either. In a steady state the two are one offset (mcg-fit
# friction, which knows no dead band, reports their sum as friction: 1.2 V); the coasts at 0 V
# (friction brakes, the dead band does nothing) and the reversals tell them apart.
#  - mcg-fit gap names the dead band and the friction together (hbridge+friction_levels), with
#    shrink >= 60 % on the held-out run and the dead band and the Coulomb level within 3 % of
#    the truth. Before, the joint fit stopped with its budget spent half way along the valley
#    where the two trade (dead band 0.041, Tc 19 % high) and brush_drop+friction_levels (a
#    0.31 V brush drop the motor does not have) was the diagnosis.
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sim mcg-fit

small_motor_ini 0.0051 0.0036 2e-6 >"$work/truth.ini"
printf '[effect.hbridge]\nR_on_ohm = 0\ndeadband = 0.05\n' >>"$work/truth.ini"
small_motor_ini 0 0 0 >"$work/given.ini"

# program SEGMENTS: the inputs at 2 kHz (segments in lib.sh)
program() { segments 0.0005 "$1"; }
# measure SEED: the truth's run of the inputs on stdin, measured by the encoder, speed only
measure() { encoder_speed_only "$work/truth.ini" 0.0005 "$1"; }
program "hold 0 0.2;hold 3 0.5;hold 6 0.5;hold 9 0.5;hold 0 0.5;hold -3 0.5;hold -6 0.5;hold 0 0.5;\
ramp 0 2 3;hold 0 0.5;ramp 0 -2 3;hold 0 0.5" | measure 1 >"$work/train.csv"
program "hold 0 0.2;hold 4 0.5;hold 8 0.5;hold 0 0.5;hold -4 0.5;hold -8 0.5;hold 0 0.5;\
ramp 0 1.8 2;hold 0 0.5;ramp 0 -1.8 2;hold 0 0.5" | measure 2 >"$work/validate.csv"

mcg-fit gap --budget 900 --config "$work/given.ini" \
  --train "$work/train.csv" --validate "$work/validate.csv" \
  >"$work/gap.csv" 2>"$work/gap.err" || fail "gap: exit $?: $(tail -1 "$work/gap.err")"
row=$(grep -v '^#' "$work/gap.csv" | sed -n 2p)
echo "gap: $(cut -d, -f1,4,15 <<<"$row")"
if [[ "$(cut -d, -f1 <<<"$row")" != hbridge+friction_levels ]]; then
  fail "gap: diagnosis $(cut -d, -f1 <<<"$row"), expected hbridge+friction_levels"
else
  pass
  shrink=$(cut -d, -f4 <<<"$row")
  if awk -v s="$shrink" 'BEGIN { exit !(s >= 60) }'; then pass; else fail "gap: shrink $shrink % < 60 %"; fi
  param() { grep -o "$1=[^+ ,]*" <<<"$row" | cut -d= -f2; }
  near "gap: hbridge.deadband" "$(param hbridge.deadband)" 0.05 0.03
  near "gap: friction_levels.Tc_Nm" "$(param friction_levels.Tc_Nm)" 0.0036 0.03
  near "gap: friction_levels.c1_Nm_s_rad" "$(param friction_levels.c1_Nm_s_rad)" 2e-6 0.03
fi
finish gap_deadband
