#!/usr/bin/env bash
# A small 12 V motor (speed only, 1 kHz, 16384 counts/rev) behind a driver that coasts in the
# PWM off-time (pwm_coast 0.85: the current dies out in most of it, as behind a DRV8833 in
# coast mode) AND Coulomb friction worth 0.6 V of drive, described from its datasheet without
# either, driven by staircases both ways. The back-emf acts only while the current flows, so at
# 1 V the motor runs at 110 rad/s where a braking drive would give 26 (and the datasheet model
# 67): the speed rises far faster than the duty at low duty, and at duty 0 the shaft coasts.
#  - mcg-fit gap names the coasting driver and the friction together (pwm_coast+
#    friction_levels), shrink >= 60 % on the held-out run, the share and the Coulomb level
#    within 5 % of the truth. Friction alone cannot bend the static curve that way.
#  - The viscous term, small beside the coasting driver's, trades exactly with Kt on speed alone:
#    the fit drove it to its bound 0 with Kt_scale above 1 (and it was then pinned there). With
#    Kt_scale held as the gauge it is set by the runs, within 5 % of the truth; the breakaway
#    keeps its profile.
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sim mcg-fit

small_motor_ini 0.0045 0.0036 2e-6 >"$work/truth.ini"
printf '[effect.pwm_coast]\ncoast = 0.85\n' >>"$work/truth.ini"
small_motor_ini 0 0 0 >"$work/given.ini"

# program SEGMENTS: the inputs at 1 kHz (segments in lib.sh)
program() { segments 0.001 "$1"; }
# measure SEED: the truth's run of the inputs on stdin, measured by the encoder, speed only
measure() { encoder_speed_only "$work/truth.ini" 0.001 "$1"; }
program "hold 0 0.2;hold 1 0.6;hold 2 0.6;hold 3.5 0.6;hold 6 0.6;hold 10 0.6;hold 0 0.6;\
hold -1 0.6;hold -2.5 0.6;hold -5 0.6;hold -9 0.6;hold 0 0.6;ramp 0 2 3;hold 0 0.5;ramp 0 -2 3;\
hold 0 0.5" | measure 1 >"$work/train.csv"
program "hold 0 0.2;hold 1.5 0.6;hold 4 0.6;hold 8 0.6;hold 0 0.6;hold -1.5 0.6;hold -4 0.6;\
hold -8 0.6;hold 0 0.6;ramp 0 1.8 2;hold 0 0.5" | measure 2 >"$work/validate.csv"

mcg-fit gap --budget 900 --config "$work/given.ini" \
  --train "$work/train.csv" --validate "$work/validate.csv" \
  >"$work/gap.csv" 2>"$work/gap.err" || fail "gap: exit $?: $(tail -1 "$work/gap.err")"
row=$(grep -v '^#' "$work/gap.csv" | sed -n 2p)
echo "gap: $(cut -d, -f1,4,15 <<<"$row")"
if [[ "$(cut -d, -f1 <<<"$row")" != pwm_coast+friction_levels ]]; then
  fail "gap: diagnosis $(cut -d, -f1 <<<"$row"), expected pwm_coast+friction_levels"
else
  pass
  shrink=$(cut -d, -f4 <<<"$row")
  if awk -v s="$shrink" 'BEGIN { exit !(s >= 60) }'; then pass; else fail "gap: shrink $shrink % < 60 %"; fi
  param() { grep -o "$1=[^+ ,]*" <<<"$row" | cut -d= -f2; }
  near "gap: pwm_coast.coast" "$(param pwm_coast.coast)" 0.85 0.05
  near "gap: friction_levels.Tc_Nm" "$(param friction_levels.Tc_Nm)" 0.0036 0.05
  # Kt and the viscous level trade exactly on speed alone: with Kt_scale held as the gauge the
  # level is set by the runs.
  check "gap: Kt_scale is held as the gauge the viscous level trades with" \
    grep -qF "param_mismatch.Kt_scale pinned at the given value (a gauge)" <<<"$row"
  near "gap: friction_levels.c1_Nm_s_rad" "$(param friction_levels.c1_Nm_s_rad)" 2e-6 0.05
  if grep -q "friction_levels.Ts_excess_Nm=[0-9.e-]*+-[0-9]" <<<"$row" &&
    grep -qF "friction_levels.Ts_excess_Nm profiled on the exact stick" <<<"$row"; then
    pass
  else
    fail "gap: the breakaway lost its profile: $(cut -d, -f15,17 <<<"$row")"
  fi
fi
finish gap_coast
