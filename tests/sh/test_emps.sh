#!/usr/bin/env bash
# Real data: EMPS (a current-driven Maxon DC motor on a ball screw, closed-loop position
# moves; Janot, Gautier, Brunot 2019). mcg-fit friction on the estimation run, from the
# logged force and the motor encoder's position only, must give the Coulomb and viscous
# friction within two of its standard errors of the published IDIM-LS values
# (Fc = 20.3935 N, Fv = 203.5034 N s/m), in SI units. On the validation run (the same moves
# with force pulses) its values must lie within two standard errors of the same IDIM-LS recipe
# run on that file (Fc = 20.90 N, Fv = 210.09 N s/m, offset -3.22 N: friction moved between
# the runs, see PROVENANCE.md). The data ship in tests/data/real/emps (Apache-2.0).
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
src=$2
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
finish emps
