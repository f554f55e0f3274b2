#!/usr/bin/env bash
# Real data: UNDCMotor's open-loop runs (a 100:1 gearmotor behind a PWM driver that coasts, the
# voltage as commanded, the output shaft's speed from encoder counts over 20 ms; Bermeo 2024, MIT;
# tests/data/real/undcmotor, PROVENANCE.md). The driver is stated in frictionless.ini (pwm_coast).
#  - mcg-fit friction on the step run (the voltage balance of the coasting driver) gives the
#    Coulomb level within two of its standard errors of the static curve's (model.ini, from an
#    independent measurement of the same rig) and a positive viscous term: the braking balance
#    reads the coasting motor's back-emf as a viscous term of -0.0105 N m s/rad;
#  - mcg-fit gap on the output shaft given without friction, with the set's gap.args (trained on
#    the step run, scored on the PRBS run; the benchmark's row), names friction, closes >= 60 % of
#    the validation run's speed error, and its Coulomb and viscous levels lie within two of its
#    standard errors of what mcg-fit friction finds in the same training run;
#  - the same, with the driver described as braking (frictionless.ini without its pwm_coast):
#    gap names the coasting driver and the friction together (pwm_coast+friction_levels), with
#    the driver coasting throughout and friction's Coulomb level as above. A coasting share fitted
#    first without friction holds the speeds down in its place, and a joint fit begun there ends
#    with friction 0 (a verdict of unexplained).
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
dir="$src/tests/data/real/undcmotor"
source "$(dirname "$0")/lib.sh"
require_tools mcg-fit
export PATH="$tools:$PATH"

# ini_value KEY INI and ini_se KEY INI: "KEY = value  ; +- se UNIT" (the first, [motor]).
ini_value() { awk -v k="$1" '$1 == k && $2 == "=" { print $3; exit }' "$2"; }
ini_se() { awk -v k="$1" '$1 == k && $2 == "=" { print $6; exit }' "$2"; }
# gap_field NAME 1 and gap_field NAME 2: NAME's value and standard error in gap's fitted parameters.
gap_field() {
  awk -v k="$1" -v f="$2" '/^fitted parameters/ { sub(/^[^:]*: /, ""); n = split($0, p, " ")
    for (j = 1; j <= n; j++) { split(p[j], kv, "="); split(kv[2], vs, "[+]-"); if (kv[1] == k) print vs[f] } }' \
    "$work/gap.txt"
}

mcg-fit friction --config "$dir/frictionless.ini" --order 1 --no-static "$dir/undcmotor_step_open.csv" \
  >"$work/friction.ini"
tc=$(ini_value Tc_Nm "$work/friction.ini")
tc_se=$(ini_se Tc_Nm "$work/friction.ini")
c1=$(ini_value visc1_Nm_s_rad "$work/friction.ini")
c1_se=$(ini_se visc1_Nm_s_rad "$work/friction.ini")
within_se "friction on the step run: Tc_Nm (the static curve's in model.ini)" "$tc" "$tc_se" \
  "$(ini_value Tc_Nm "$dir/model.ini")"
expect "friction on the step run: visc1 = $c1 +- $c1_se N m s/rad is positive beyond two errors" \
  "awk -v c='$c1' -v s='$c1_se' 'BEGIN { exit !(s > 0 && c > 2 * s) }'"

gap_on_real "$dir" '*friction*' "the frictionless output shaft"
gap_closes_most "$work/gap.txt"
within_se "gap's friction_levels.Tc_Nm (friction's on the training run)" "$(gap_field friction_levels.Tc_Nm 1)" \
  "$(gap_field friction_levels.Tc_Nm 2)" "$tc"
within_se "gap's friction_levels.c1_Nm_s_rad (friction's visc1)" "$(gap_field friction_levels.c1_Nm_s_rad 1)" \
  "$(gap_field friction_levels.c1_Nm_s_rad 2)" "$c1"
warnings_hold_values "$work/gap.txt"

awk '/^\[/ { skip = ($0 == "[effect.pwm_coast]") } !skip' "$dir/frictionless.ini" >"$work/braking.ini"
gap_on_real "$dir" pwm_coast+friction_levels "the output shaft behind a braking driver" \
  "frictionless.ini=$work/braking.ini"
expect "given a braking driver, gap's pwm_coast.coast = $(gap_field pwm_coast.coast 1) is 1 (coasting throughout)" \
  "awk -v c='$(gap_field pwm_coast.coast 1)' 'BEGIN { exit !(c > 0.95) }'"
within_se "given a braking driver, gap's friction_levels.Tc_Nm (friction's on the training run)" \
  "$(gap_field friction_levels.Tc_Nm 1)" "$(gap_field friction_levels.Tc_Nm 2)" "$tc"
warnings_hold_values "$work/gap.txt"
finish undcmotor_runs
