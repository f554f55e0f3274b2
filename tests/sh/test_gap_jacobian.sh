#!/usr/bin/env bash
# mcg-fit gap with its fits' Jacobians by sensitivities (--jacobian sensitivities) against the
# same search by finite differences: the same diagnosis, and its fitted parameters within two
# standard errors of the other's (a withheld dead time, training on a PRBS, validating on steps; a
# brush drop on a staircase through zero). Not closer: a dead time of whole rows is a kink of the
# sampled run (model/sensitivity.hpp), and the two Jacobians take its two sides there.
# Args: TOOL_DIR SOURCE_DIR. Runs the built tools; a few seconds per diagnosis.
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sweep mcg-sim mcg-fit

# The first data row's effect and its parameters (column params) as "name value se" lines.
diagnosis() { grep -v '^#' "$1" | awk -F, 'NR == 2 {print $1; exit}'; }
parameters() {
  grep -v '^#' "$1" | awk -F, 'NR == 1 {for (k = 1; k <= NF; k++) if ($k == "params") c = k}
    NR == 2 {n = split($c, p, " "); for (k = 1; k <= n; k++) if (p[k] ~ /\+-/) {
      split(p[k], a, "="); split(a[2], b, "\\+-"); print a[1], b[1], b[2]}; exit}'
}
# The diagnosis' own parameters in both files, and every parameter both fit, within two of the
# larger standard error and the printed 4 digits (a weakly set one, a static scale at +- 50 %, may be fitted by one and
# pinned by the other: an infinite error is pinned, and the two Jacobians differ in the last
# digits).
agree() {
  parameters "$1" >"$work/a.txt"
  parameters "$2" >"$work/b.txt"
  local effect
  effect=$(diagnosis "$1")
  awk -v effect="$effect" 'NR == FNR {v[$1] = $2; se[$1] = $3; next}
    {seen[$1] = 1; if (!($1 in v)) {if (index($1, effect ".") == 1) {print "only in one:", $1; bad = 1}; next}
     s = se[$1] > $3 ? se[$1] : $3; d = v[$1] - $2; if (d < 0) d = -d
     m = v[$1] < 0 ? -v[$1] : v[$1]; e = m > 0 ? log(m) / log(10) : 0; f = int(e); if (f > e) f--
     if (d > 2 * s + 10 ^ (f - 3)) {print "differs:", $1, v[$1], se[$1], $2, $3; bad = 1}}
    END {for (k in v) if (index(k, effect ".") == 1 && !(k in seen)) {print "only in one:", k; bad = 1}
         exit bad}' "$work/a.txt" "$work/b.txt"
}

measure_dead_time() { mcg-sim --encoder --noise-i 0.003 --adc --seed "$1" --effect dead_time:tau_d_s=0.004; }
mcg-sweep prbs --bias 6 --amp 3 --clock 0.006 --duration 3 --clutch 0 --seed 5 | measure_dead_time 1 \
  >"$work/dt_train.csv"
mcg-sweep step --level 4 --at 0.1 --then 9@0.6,6@1.1,12@1.6,3@2.1 --duration 3 --clutch 0 | measure_dead_time 2 \
  >"$work/dt_validate.csv"
measure_drop() { mcg-sim --encoder --noise-i 0.003 --adc --seed "$1" --effect brush_drop:V_b_V=0.6; }
mcg-sweep staircase --amp 10 --steps 5 --hold 0.3 --clutch 0 | measure_drop 3 >"$work/bd_train.csv"
mcg-sweep prbs --bias 0 --amp 8 --clock 0.05 --duration 3 --clutch 0 --seed 6 | measure_drop 4 \
  >"$work/bd_validate.csv"
for case in dt bd; do
  for how in differences sensitivities; do
    mcg-fit gap --train "$work/${case}_train.csv" --validate "$work/${case}_validate.csv" --jacobian "$how" \
      --budget 600 >"$work/${case}_$how.csv" 2>"$work/${case}_$how.err"
  done
done
check "dead time: the diagnosis is dead_time" eval '[[ $(diagnosis "$work/dt_differences.csv") == dead_time ]]'
check "dead time: the same diagnosis by sensitivities" \
  eval '[[ $(diagnosis "$work/dt_sensitivities.csv") == $(diagnosis "$work/dt_differences.csv") ]]'
check "dead time: the same parameters within two standard errors" agree "$work/dt_differences.csv" \
  "$work/dt_sensitivities.csv"
check "brush drop: the diagnosis is brush_drop" eval '[[ $(diagnosis "$work/bd_differences.csv") == brush_drop ]]'
check "brush drop: the same diagnosis by sensitivities" \
  eval '[[ $(diagnosis "$work/bd_sensitivities.csv") == $(diagnosis "$work/bd_differences.csv") ]]'
check "brush drop: the same parameters within two standard errors" agree "$work/bd_differences.csv" \
  "$work/bd_sensitivities.csv"
finish gap_jacobian
