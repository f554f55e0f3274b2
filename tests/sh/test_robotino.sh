#!/usr/bin/env bash
# Real data: the three drive motors of a Festo Robotino (Dunkermotoren GR 42x25, closed-loop speed
# staircases; Brylev 2023, Apache-2.0; tests/data/real/robotino). The logged armature current is
# the drive input. mcg-fit friction on each motor's estimation run (the torque Kt i with the
# datasheet's Kt, the speed logged at the motor shaft) must give the Coulomb and viscous friction
# within two of its standard errors of the authors' own grey-box values for that motor
# (PROVENANCE.md). mcg-fit gap on motor 1 given without friction (frictionless.ini, --current),
# with its gap.args (the benchmark's row), must name friction and close >= 60 % of the validation
# run's speed error. Args: TOOL_DIR SOURCE_DIR.
set -euo pipefail
tools=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
dir="$src/tests/data/real/robotino"
source "$(dirname "$0")/lib.sh"
require_tools mcg-fit
export PATH="$tools:$PATH"

# The authors' fitted friction per motor: T_0 (N m) and b (N m s/rad).
published_Tc=(0.0081312 0.0069712 0.0080917)
published_b=(2.3685e-5 2.0285e-5 2.3637e-5)
Kt=$(awk -F' *= *' '/^Kt_Nm_A/ { print $2 }' "$dir/frictionless.ini")

# within KEY PUBLISHED INI: "KEY = value  ; +- se UNIT" (the first, [motor]) is within two
# standard errors of PUBLISHED.
within() {
  local key=$1 published=$2 ini=$3 line value se
  line=$(grep -m1 "^$key = " "$ini") || { fail "$key: not written in $(basename "$ini")"; return; }
  value=$(awk '{ print $3 }' <<<"$line")
  se=$(awk '{ print $6 }' <<<"$line")
  if awk -v v="$value" -v s="$se" -v p="$published" \
    'BEGIN { d = v - p; if (d < 0) d = -d; exit !(s > 0 && d <= 2 * s) }'; then
    pass
    echo "ok   $key = $value +- $se (published $published, $(basename "$ini"))"
  else
    fail "$key = $value +- $se: published $published is not within two standard errors ($(basename "$ini"))"
  fi
}

for m in 1 2 3; do
  run="$dir/robotino_m${m}_estimation.csv"
  awk -F, -v kt="$Kt" 'NR == 1 { print $0 ",T_Nm"; next } { printf "%s,%.8g\n", $0, kt * $3 }' "$run" \
    >"$work/m$m.csv"
  # The current is signed by the speed (zero at rest), so no breakaway can be read: --no-static.
  mcg-fit friction --config "$dir/frictionless.ini" --torque T_Nm --no-static --order 1 "$work/m$m.csv" \
    >"$work/m$m.ini"
  within Tc_Nm "${published_Tc[m - 1]}" "$work/m$m.ini"
  within visc1_Nm_s_rad "${published_b[m - 1]}" "$work/m$m.ini"
done

gap_on_real "$dir" '*friction*' "the frictionless motor"
gap_closes_most "$work/gap.txt"
warnings_hold_values "$work/gap.txt"
finish robotino
