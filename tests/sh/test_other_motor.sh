#!/usr/bin/env bash
# mcg-fit model on motors other than the rig's Pittman, measured by speed only:
#  - a small 12 V motor alone sampled at 2 kHz, an encoder of 16384 counts/rev over 0.5 ms;
#  - a 30:1 gearmotor sampled at 100 Hz, its speed measured at the output shaft.
# The given model has R and L measured (right) and Kt = Ke, J and Tc wrong by 20-70 %.
# The default free set (J, Kt = Ke, Tc) recovers them within 2 % and says converged = yes;
# freeing R with Kt on speed-only data is flagged (correlations beyond 0.99, exit 3); given
# without friction, the gap diagnosis names the missing friction levels; the gearmotor behind a
# bridge with a wide dead zone gets hbridge, its volt gauge pinned on R (with Kt and R free or fixed).
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sweep mcg-sim mcg-fit

# motor_ini R L K J Ts Tc c1: a 12 V motor alone
motor_ini() {
  printf '[motor]\nR_ohm = %s\nL_H = %s\nKt_Nm_A = %s\nKe_V_s_rad = %s\nJ_kg_m2 = %s\nTs_Nm = %s\nTc_Nm = %s\n' \
    "$1" "$2" "$3" "$3" "$4" "$5" "$6"
  printf 'visc1_Nm_s_rad = %s\nvisc2_Nm_s2_rad2 = 0\nvisc3_Nm_s3_rad3 = 0\n[drive]\nsupply_V = 12\n' "$7"
}

# within FILE KEY WANT TOL: the first "KEY = value" of FILE within TOL (relative) of WANT
within() {
  local value
  value=$(grep -m1 "^$2 = " "$1" | awk '{ print $3 }')
  if awk -v v="$value" -v w="$3" -v t="$4" 'BEGIN { d = v - w; if (d < 0) d = -d; exit !(d <= t * w) }'; then
    echo "ok   $(basename "$1") $2 = $value (truth $3)"
  else
    fail "$(basename "$1") $2 = $value, truth $3 (tolerance $4)"
  fi
}

# fit_case NAME TRUTH GIVEN RATIO RUN VALIDATE: default fit, then the degenerate set.
fit_case() {
  local name=$1 truth=$2 ratio=$4
  local fit="$work/$name.ini"
  if ! mcg-fit model --config "$3" --outputs rpm --gear-ratio "$ratio" "$5" >"$fit" 2>"$work/$name.err"; then
    fail "$name: default fit exited non-zero: $(tail -1 "$work/$name.err")"
    return
  fi
  grep -q '^converged = yes' "$fit" || fail "$name: not converged = yes"
  grep -q '^free = motor.J_kg_m2 motor.Kt_Nm_A motor.Tc_Nm$' "$fit" || fail "$name: default free set $(grep '^free' "$fit")"
  grep -q '^Ke_V_s_rad = .*tied to motor.Kt_Nm_A' "$fit" || fail "$name: Ke not tied to Kt"
  local key
  for key in Kt_Nm_A J_kg_m2 Tc_Nm; do
    within "$fit" "$key" "$(grep -m1 "^$key = " "$truth" | awk '{ print $3 }')" 0.02
  done
  within "$fit" R_ohm "$(grep -m1 '^R_ohm = ' "$truth" | awk '{ print $3 }')" 0
  # The fitted model scored on a run it has not seen.
  local fit_pct
  fit_pct=$(mcg-fit model --evaluate --config "$fit" --outputs rpm --gear-ratio "$ratio" "$6" | awk -F' = ' '/fit_rpm/ { print $2 + 0 }')
  awk -v f="$fit_pct" 'BEGIN { exit !(f > 95) }' && echo "ok   $name: validation fit $fit_pct %" ||
    fail "$name: validation fit $fit_pct %"
  # R and Kt together from speed alone: flagged, exit 3 (R is one of a scaling family with J and Kt: the
  # pair named is whichever correlates most in this fit).
  local status=0
  mcg-fit model --config "$3" --outputs rpm --gear-ratio "$ratio" --max-evaluations 150 \
    --free motor.J_kg_m2,motor.R_ohm,motor.Kt_Nm_A,motor.Tc_Nm --tie motor.Ke_V_s_rad=motor.Kt_Nm_A \
    "$5" >"$work/$name-degenerate.ini" 2>"$work/$name-degenerate.err" || status=$?
  if [[ $status -ne 3 ]] || ! grep -q '^converged = no' "$work/$name-degenerate.ini" ||
    ! grep -Eq '^mcg-fit: warning: (motor\.R_ohm and .*|.* and motor\.R_ohm) are correlated' "$work/$name-degenerate.err"; then
    fail "$name: R and Kt free on speed-only data not flagged (exit $status)"
  else
    echo "ok   $name: R and Kt together flagged ($(grep -c '^mcg-fit: warning' "$work/$name-degenerate.err") warnings)"
  fi
}

# Small 12 V motor: 2 kHz, 16384 counts/rev over 0.5 ms.
motor_ini 2.4 0.0003 0.0135 1.8e-6 0.0016 0.0011 2.5e-6 >"$work/small-truth.ini"
motor_ini 2.4 0.0003 0.011 2.5e-6 0.0016 0.0005 2.5e-6 >"$work/small-given.ini"
for seed in 3 4; do
  mcg-sweep prbs --dt 0.0005 --amp 4 --bias 5 --clock 0.04 --duration 3 --clutch 0 --seed $seed |
    mcg-sim --config "$work/small-truth.ini" --encoder --window 0.0005 --counts-per-rev 16384 --seed $seed \
      >"$work/small-$seed.csv"
done
fit_case small "$work/small-truth.ini" "$work/small-given.ini" 1 "$work/small-3.csv" "$work/small-4.csv"

# The same motor given without any friction: mcg-fit gap names the missing friction as
# additive levels (its scales would multiply zero) and finds the Coulomb and viscous levels.
motor_ini 2.4 0.0003 0.0135 1.8e-6 0 0 0 >"$work/small-frictionless.ini"
mcg-fit gap --config "$work/small-frictionless.ini" --train "$work/small-3.csv" --validate "$work/small-4.csv" \
  >"$work/small-gap.csv" 2>"$work/small-gap.err" || fail "small gap: exit $?: $(tail -1 "$work/small-gap.err")"
row=$(grep -v '^#' "$work/small-gap.csv" | sed -n 2p)
if [[ "$(cut -d, -f1 <<<"$row")" != friction_levels ]]; then
  fail "small gap: diagnosis $(cut -d, -f1 <<<"$row"), expected friction_levels"
else
  tc=$(grep -o 'friction_levels.Tc_Nm=[^+]*' <<<"$row" | cut -d= -f2)
  c1=$(grep -o 'friction_levels.c1_Nm_s_rad=[^+]*' <<<"$row" | cut -d= -f2)
  if awk -v tc="$tc" -v c1="$c1" 'BEGIN { exit !(tc > 0.0011 * 0.95 && tc < 0.0011 * 1.05 && c1 > 2.5e-6 * 0.9 && c1 < 2.5e-6 * 1.1) }'; then
    echo "ok   small gap: friction_levels, Tc = $tc N m (truth 0.0011), c1 = $c1 (truth 2.5e-6)"
  else
    fail "small gap: friction_levels with Tc = $tc, c1 = $c1 (truth 0.0011, 2.5e-6)"
  fi
fi

# 30:1 gearmotor at 100 Hz, 360 counts/rev on the motor over 10 ms, speed at the output.
motor_ini 4.2 0.00015 0.0062 6e-7 0.0005 0.0004 4e-7 >"$work/gear-truth.ini"
motor_ini 4.2 0.00015 0.005 1e-6 0.0005 0.0002 4e-7 >"$work/gear-given.ini"
for seed in 5 6; do
  mcg-sweep prbs --dt 0.01 --amp 5 --bias 6 --clock 0.2 --duration 8 --clutch 0 --seed $seed |
    mcg-sim --config "$work/gear-truth.ini" --encoder --window 0.01 --counts-per-rev 360 --seed $seed |
    awk -F, -v OFS=, '/^#/ || /^t,/ { print; next } { $5 /= 30; $6 /= 30; $7 /= 30; print }' >"$work/gear-$seed.csv"
done
fit_case gear "$work/gear-truth.ini" "$work/gear-given.ini" 30 "$work/gear-5.csv" "$work/gear-6.csv"

# The gearmotor behind a bridge with a wide dead zone (15 % of the duty, 1.8 V): the gap
# diagnosis at 100 Hz, speed at the output (its circuit, 36 us, is solved as algebraic, so no
# candidate crawls at microsecond steps). The low drive level (-1 V) lies inside the dead zone,
# so the data never see the volt: Kt, R, J and friction scale together with the bridge's output
# (a gauge; hbridge alone fits at deadband 0.088 +- 14 with every scale 1.10 +- 24). The search
# pins R, then Kt, at the given values and names the bridge with its parameters back (before,
# hbridge was set aside and brush_drop, 8x the current noise, was named). With Kt and R pinned
# by the user the bridge is named the same.
for seed in 5 6; do
  mcg-sweep prbs --dt 0.01 --amp 5 --bias 4 --clock 0.2 --duration 8 --clutch 0 --seed $seed |
    mcg-sim --config "$work/gear-truth.ini" --effect hbridge:R_on_ohm=0.3,deadband=0.15 --encoder --window 0.01 \
      --counts-per-rev 360 --seed $seed |
    awk -F, -v OFS=, '/^#/ || /^t,/ { print; next } { $5 /= 30; $6 /= 30; $7 /= 30; print }' >"$work/dead-$seed.csv"
done
mcg-fit gap --config "$work/gear-truth.ini" --gear-ratio 30 --train "$work/dead-5.csv" --validate "$work/dead-6.csv" \
  >"$work/dead-free.csv" 2>"$work/dead-free.err" || fail "dead zone gap, Kt free: exit $?: $(tail -1 "$work/dead-free.err")"
row=$(grep -v '^#' "$work/dead-free.csv" | sed -n 2p)
db=$(grep -o 'hbridge.deadband=[^+]*' <<<"$row" | cut -d= -f2)
if [[ "$(cut -d, -f1 <<<"$row")" == hbridge ]] && [[ "$row" == *"param_mismatch.R_scale"*"pinned at the given value (a gauge)"* ]] &&
  awk -v d="$db" 'BEGIN { exit !(d > 0.15 * 0.95 && d < 0.15 * 1.05) }'; then
  echo "ok   dead zone gap, Kt free: hbridge, deadband $db (truth 0.15), the gauge pinned on R"
else
  fail "dead zone gap, Kt free: $(cut -d, -f1 <<<"$row") deadband $db, expected hbridge at 0.15 with R pinned"
fi
mcg-fit gap --config "$work/gear-truth.ini" --gear-ratio 30 --fix motor.Kt_Nm_A=0.0062,motor.R_ohm=4.2 \
  --train "$work/dead-5.csv" --validate "$work/dead-6.csv" \
  >"$work/dead-gap.csv" 2>"$work/dead-gap.err" || fail "dead zone gap: exit $?: $(tail -1 "$work/dead-gap.err")"
row=$(grep -v '^#' "$work/dead-gap.csv" | sed -n 2p)
db=$(grep -o 'hbridge.deadband=[^+]*' <<<"$row" | cut -d= -f2)
if [[ "$(cut -d, -f1 <<<"$row")" == hbridge ]] && awk -v s="$(cut -d, -f7 <<<"$row")" -v d="$db" \
  'BEGIN { exit !(s >= 90 && d > 0.15 * 0.95 && d < 0.15 * 1.05) }'; then
  echo "ok   dead zone gap: hbridge, gap shrink $(cut -d, -f7 <<<"$row") %, deadband $db (truth 0.15)"
else
  fail "dead zone gap: $(cut -d, -f1,7 <<<"$row") deadband $db, expected hbridge closing 90 % of the gap, deadband 0.15"
fi

[[ $failures -eq 0 ]]
