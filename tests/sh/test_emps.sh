#!/usr/bin/env bash
# Real data: EMPS (a current-driven Maxon DC motor on a ball screw, closed-loop position
# moves; Janot, Gautier, Brunot 2019). mcg-fit friction on the estimation run, from the
# logged force and the motor encoder's position only, must give the Coulomb and viscous
# friction within two of its standard errors of the published IDIM-LS values
# (Fc = 20.3935 N, Fv = 203.5034 N s/m), in SI units. On the validation run (the same moves
# with force pulses) its values must lie within two standard errors of the same IDIM-LS recipe
# run on that file (Fc = 20.90 N, Fv = 210.09 N s/m, offset -3.22 N: friction moved between
# the runs, see PROVENANCE.md). mcg-fit model, driven by the logged force (--torque) from the
# axis given without friction (frictionless.ini, a start of Tc 15 N and Fv 150 N s/m), freed
# the force's constant offset beside the friction (friction_asymmetry.dT_Nm, the same constant
# as friction's offset), must land within two of its standard errors of the published Fc and
# Fv, with the offset within 0.5 N of friction's; so must it on the force with that offset
# removed. mcg-fit gap on the same model with its gap.args (the benchmark's row) must
# name friction with the drive's offset (friction_levels+friction_asymmetry), close >= 60 % of
# the validation run's speed error, and give the published Fc and Fv within two of its
# standard errors, J within 5 % of the published mass. The data ship in tests/data/real/emps
# (Apache-2.0).
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
data="$src/tests/data/real/emps/emps_estimation.csv"
validation="$src/tests/data/real/emps/emps_validation.csv"
[[ -x "$tools/mcg-fit" ]] || { echo "skipped: mcg-fit not built"; exit 125; }
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"

fit_run() {
  mcg-fit friction --linear --torque force_N --position qm_m --fit-inertia --offset --no-static --order 1 "$1"
}
fit_run "$data" >"$work/fit.ini"
fit_run "$validation" >"$work/validation.ini"

# published KEY PUBLISHED [INI]: value and standard error from "KEY = value  ; +- se UNIT"
published() {
  local key=$1 published=$2 ini=${3:-$work/fit.ini} line value se
  line=$(grep "^$key = " "$ini") || { fail "$key: not written"; return; }
  value=$(awk '{ print $3 }' <<<"$line")
  se=$(awk '{ print $6 }' <<<"$line")
  if awk -v v="$value" -v s="$se" -v p="$published" 'BEGIN { d = v - p; if (d < 0) d = -d; exit !(s > 0 && d <= 2 * s) }'; then
    pass
    echo "ok   $key = $value +- $se (reference $published, $(basename "$ini"))"
  else
    fail "$key = $value +- $se: reference $published is not within two standard errors"
  fi
}
published state0.total_Tc_N 20.3935
published state0.total_visc1_N_s_m 203.5034
published state0.offset_N -3.1648
published state0.total_Tc_N 20.90 "$work/validation.ini"
published state0.total_visc1_N_s_m 210.09 "$work/validation.ini"
published state0.offset_N -3.22 "$work/validation.ini"

# The model's own fit, from the frictionless axis: the fitted Tc_Nm and visc1_Nm_s_rad (N, N s/m
# at a gear ratio of 1) of [motor], "KEY = value  ; fitted, +- se UNIT".
dir="$src/tests/data/real/emps"
printf '[motor]\nTc_Nm = 15\nvisc1_Nm_s_rad = 150\n' >"$work/start.ini"
model_fit() {
  mcg-fit model --config "$dir/frictionless.ini" --config "$work/start.ini" --torque force_N --position qm_m \
    --free motor.J_kg_m2,motor.Tc_Nm,motor.visc1_Nm_s_rad,friction_asymmetry.dT_Nm "$1"
}
fitted() {
  local key=$1 published=$2 ini=$3 line value se
  line=$(grep -m1 "^$key = .*; fitted" "$ini") || { fail "$key: not fitted in $(basename "$ini")"; return; }
  value=$(awk '{ print $3 }' <<<"$line")
  se=$(awk '{ print $7 }' <<<"$line")
  if awk -v v="$value" -v s="$se" -v p="$published" 'BEGIN { d = v - p; if (d < 0) d = -d; exit !(s > 0 && d <= 2 * s) }'; then
    pass
    echo "ok   model $key = $value +- $se (published $published, $(basename "$ini"))"
  else
    fail "model $key = $value +- $se: published $published is not within two standard errors"
  fi
}
model_fit "$data" >"$work/model.ini"
fitted Tc_Nm 20.3935 "$work/model.ini"
fitted visc1_Nm_s_rad 203.5034 "$work/model.ini"
offset=$(awk '/^state0.offset_N = / { print $3 }' "$work/fit.ini")
# The drive's offset: the model's bias and friction's offset are one constant, sign included.
dT=$(awk '/^dT_Nm = .*; fitted/ { print $3 }' "$work/model.ini")
if [[ -n $dT ]] && awk -v a="$dT" -v b="$offset" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= 0.5) }'; then
  pass
  echo "ok   model's drive offset dT_Nm = $dT (friction's offset $offset)"
else
  fail "model's drive offset dT_Nm = '${dT:-not fitted}' is not within 0.5 N of friction's offset $offset"
fi
grep -q "^se_jackknife_stretches = " "$work/model.ini" && grep -q "^motor.Tc_Nm.se_jackknife = " "$work/model.ini" &&
  pass || fail "model: the jackknife's standard errors are not reported beside the Jacobian's"
awk -F, -v o="$offset" '/^#/ { print; next } $1 == "t" { print; next } { printf "%s,%s,%.10g\n", $1, $2, $3 - o }' \
  "$data" >"$work/estimation_no_offset.csv"
model_fit "$work/estimation_no_offset.csv" >"$work/model_no_offset.ini"
fitted Tc_Nm 20.3935 "$work/model_no_offset.ini"
fitted visc1_Nm_s_rad 203.5034 "$work/model_no_offset.ini"

# gap on the frictionless axis, as the benchmark row runs it.
gap_on_real "$dir" friction_levels+friction_asymmetry "the frictionless axis"
# gap_param KEY REFERENCE [TOLERANCE]: "KEY=value+-se" of the fitted parameters line within two
# standard errors of REFERENCE, or within TOLERANCE of it when given.
gap_param() {
  local key=$1 reference=$2 tolerance=${3:-} item value se
  item=$(sed -n 's/^fitted parameters[^:]*: //p' "$work/gap.txt" | tr ' ' '\n' | grep "^$key=") ||
    { fail "gap: $key not fitted"; return; }
  value=${item#*=}
  value=${value%%+-*}
  se=${item##*+-}
  if awk -v v="$value" -v s="$se" -v p="$reference" -v t="$tolerance" \
    'BEGIN { d = v - p; if (d < 0) d = -d; exit !(t != "" ? d <= t : s > 0 && d <= 2 * s) }'; then
    pass
    echo "ok   gap $key = $value +- $se (reference $reference)"
  else
    fail "gap $key = $value +- $se: reference $reference is not within ${tolerance:-two standard errors}"
  fi
}
gap_param friction_levels.Tc_Nm 20.3935
gap_param friction_levels.c1_Nm_s_rad 203.5034
gap_param param_mismatch.J_scale 1.0012 0.05
gap_closes_most "$work/gap.txt"
warnings_hold_values "$work/gap.txt"
# A linear axis' parameters keep the shaft's names (so that every INI reads back) and the summary
# says what their units are along the axis; no sentence names a shaft unit.
check "gap says what the _Nm names are on a linear axis" \
  grep -qx 'linear axis: the shaft stands for the axis, a rad of it a m of travel: parameters named _Nm are in N, _Nm_s_rad in N s/m, _kg_m2 in kg, _rad_s in m/s' "$work/gap.txt"
check "no line of gap's summary names N m or kg m^2" \
  eval '! grep -E "[0-9] (N m|kg m\^2)" "$work/gap.txt"'
# Its residuals, plotted unedited, carry the axis' unit.
check "the residuals of a linear axis plot in m/s" \
  eval 'mcg-plot-gnuplot "$work/gap_residuals.csv" -y omega_res_before,omega_res_after --script "$work/res.gp" &&
    grep -qx "set ylabel '"'"'omega_res_before (m/s), omega_res_after (m/s)'"'"'" "$work/res.gp"'
finish emps
