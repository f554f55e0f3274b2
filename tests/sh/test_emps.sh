#!/usr/bin/env bash
# Real data: EMPS (a current-driven Maxon DC motor on a ball screw, closed-loop position
# moves; Janot, Gautier, Brunot 2019). mcg-fit friction on the estimation run, from the
# logged force and the motor encoder's position only, must give the Coulomb and viscous
# friction within two of its standard errors of the published IDIM-LS values
# (Fc = 20.3935 N, Fv = 203.5034 N s/m), in SI units. The data ship in tests/data/real/emps
# (Apache-2.0, see PROVENANCE.md there).
# Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$1
src=$2
data="$src/tests/data/real/emps/emps_estimation.csv"
[[ -x "$tools/mcg-fit" ]] || { echo "skipped: mcg-fit not built"; exit 125; }
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"

mcg-fit friction --linear --torque force_N --position qm_m --fit-inertia --offset --no-static --order 1 \
  "$data" >"$work/fit.ini"

# published KEY PUBLISHED: value and standard error from "KEY = value  ; +- se UNIT"
published() {
  local key=$1 published=$2 line value se
  line=$(grep "^$key = " "$work/fit.ini") || { fail "$key: not written"; return; }
  value=$(awk '{ print $3 }' <<<"$line")
  se=$(awk '{ print $6 }' <<<"$line")
  if awk -v v="$value" -v s="$se" -v p="$published" 'BEGIN { d = v - p; if (d < 0) d = -d; exit !(s > 0 && d <= 2 * s) }'; then
    pass
    echo "ok   $key = $value +- $se (published $published)"
  else
    fail "$key = $value +- $se: published $published is not within two standard errors"
  fi
}
published state0.total_Tc_N 20.3935
published state0.total_visc1_N_s_m 203.5034
published state0.offset_N -3.1648
finish emps
