#!/usr/bin/env bash
# mcg-fit gap gives the same diagnosis, parameters and scores whatever the number of threads:
# the candidates, their grid points, Jacobian columns and runs share the one pool and each
# lands at its own place, so one worker, two and three (more than the machine may have) give
# the same tables byte for byte (a withheld dead time, training on a PRBS, validating on steps).
# Args: TOOL_DIR SOURCE_DIR. Runs the built tools; a few seconds per diagnosis.
set -euo pipefail
tools=$1
export PATH="$tools:$PATH"
source "$(dirname "$0")/lib.sh"
require_tools mcg-sweep mcg-sim mcg-fit

measure() { mcg-sim --encoder --noise-i 0.003 --adc --seed "$1" --effect dead_time:tau_d_s=0.004; }
mcg-sweep prbs --bias 6 --amp 3 --clock 0.006 --duration 3 --clutch 0 --seed 5 | measure 1 >"$work/train.csv"
mcg-sweep step --level 4 --at 0.1 --then 9@0.6,6@1.1,12@1.6,3@2.1 --duration 3 --clutch 0 | measure 2 \
  >"$work/validate.csv"
for n in 1 2 3; do
  mcg-fit gap --train "$work/train.csv" --validate "$work/validate.csv" --threads "$n" --budget 600 \
    >"$work/gap$n.csv" 2>"$work/gap$n.err"
done
check "the diagnosis is dead_time" eval '[[ $(grep -v "^#" "$work/gap1.csv" | awk -F, "NR == 2 {print \$1}") == dead_time ]]'
check "one thread and two: the same candidates, parameters and scores" cmp "$work/gap1.csv" "$work/gap2.csv"
check "one thread and two: the same report" cmp "$work/gap1.err" "$work/gap2.err"
check "one thread and three: the same candidates, parameters and scores" cmp "$work/gap1.csv" "$work/gap3.csv"
check "one thread and three: the same report" cmp "$work/gap1.err" "$work/gap3.err"
finish gap_threads
