#!/usr/bin/env bash
# Runs the lab pipelines of scripts/lab/ on data made here: identification of a folder of runs
# with GNU parallel (local cores), the Slurm array's merge step, and design-and-verify.
# Usage: test_lab_scripts.sh TOOL_DIR SOURCE_DIR
set -u
tool_dir=$1
src=$2
export PATH="$tool_dir:$PATH" LC_ALL=C
command -v parallel >/dev/null || { echo "GNU parallel missing: skipped"; exit 125; }
command -v gnuplot >/dev/null || { echo "gnuplot missing: skipped"; exit 125; }
source "$(dirname "$0")/lib.sh"

# Three measured-style runs of the built-in rig, inertia changed in one of them.
mkdir -p "$work/runs"
mcg-sweep prbs --bias 6 --amp 3 --clock 0.05 --duration 3 --clutch 2 --seed 1 \
  | mcg-sim --encoder --seed 1 > "$work/runs/a.csv"
mcg-sweep prbs --bias 5 --amp 3 --clock 0.05 --duration 3 --clutch 2 --seed 2 \
  | mcg-sim --encoder --seed 2 > "$work/runs/b.csv"
printf '[motor]\nJ_kg_m2 = 9e-6\n' > "$work/heavy.ini"
mcg-sweep prbs --bias 6 --amp 2 --clock 0.05 --duration 3 --clutch 2 --seed 3 \
  | mcg-sim --encoder --seed 3 --config "$work/heavy.ini" > "$work/runs/c.csv"

"$src/scripts/lab/identify.sh" --jobs 2 --free motor.J_kg_m2,motor.Tc_Nm "$work/runs" > "$work/fits.csv" 2> "$work/fits.err"
expect "identify.sh exits 0" '[ $? = 0 ]'
expect "identify.sh writes one row per file" '[ "$(grep -vc "^#" "$work/fits.csv")" = 4 ]'
expect "identify.sh names the files in order" 'grep -q "^# file.3: .*c.csv$" "$work/fits.csv"'
expect "every fit converged" '[ "$(awk -F, "!/^#/ && NR > 1 && \$(NF-1) != 1" "$work/fits.csv" | grep -vc "^file")" = 0 ]'
j3=$(awk -F, '!/^#/ { if (!h) { for (k = 1; k <= NF; k++) if ($k == "motor.J_kg_m2") c = k; h = 1; next } if ($1 == 3) print $c }' "$work/fits.csv")
expect "the heavy run's inertia comes back (9e-6 +-10 %, got $j3)" 'awk -v j="$j3" "BEGIN { exit !(j > 8.1e-6 && j < 9.9e-6) }"'

# The Slurm array's per-task rows, merged.
ls "$work"/runs/*.csv | LC_ALL=C sort > "$work/runs.list"
mkdir -p "$work/array"
for id in 1 2 3; do
  SLURM_ARRAY_TASK_ID=$id bash "$src/scripts/lab/identify.sbatch" "$work/runs.list" "$work/array"
done
"$src/scripts/lab/merge-rows.sh" "$work/runs.list" "$work/array" > "$work/merged.csv"
expect "merge-rows.sh merges the array's rows" '[ "$(grep -vc "^#" "$work/merged.csv")" = 4 ]'

# Design a PI for 50 degrees on the report's plant and verify it on the nonlinear model.
"$src/scripts/lab/design-verify.sh" '16.557/((s/65+1)*(s/950+1))' 50 "$work/design" > "$work/design.out" 2>&1
expect "design-verify.sh exits 0" '[ $? = 0 ]'
expect "design-verify.sh writes the controller" 'grep -q "^\[controller\]" "$work/design/pi.ini"'
expect "design-verify.sh plots the step" '[ "$(head -c 4 "$work/design/verify.png" | od -An -c | tr -d " ")" = "211PNG" ]'
expect "the verified loop reaches 520 rpm" 'awk -F, "!/^#/ { if (!h) { for (k = 1; k <= NF; k++) if (\$k == \"rpm_true\" || \$k == \"rpm\") c = k; h = 1; next } last = \$c } END { exit !(last > 500 && last < 540) }" "$work/design/verify.csv"'

# Capture from the emulated board under the designed PI and a designed P, and compare with the
# model: its closed loop runs the board's own core, so the two differ by the speed reading's
# quantisation only (1.83 rpm per count of the 16 ms window).
mcg-design p --pm 55 --dt 0.001 > "$work/design/p.ini"
tty="$work/ttyMCG"
timeout 90 mcg-sim --board "$tty" > "$work/board.log" 2>&1 &
board=$!
for _ in $(seq 50); do [ -e "$tty" ] && break; sleep 0.1; done
for c in pi p; do
  timeout 40 "$src/scripts/lab/capture-compare.sh" "$tty" "$work/design/$c.ini" "$work/cc-$c" > "$work/cc-$c.out" 2>&1
  expect "capture-compare.sh exits 0 ($c)" '[ $? = 0 ]'
  rms=$(sed -n 's/.*rpm RMS difference \([0-9.]*\) rpm.*/\1/p' "$work/cc-$c.out")
  expect "board and model agree within 5 rpm RMS under the designed $c (got ${rms:-nothing})" 'awk -v r="${rms:-999}" "BEGIN { exit !(r <= 5) }"'
  expect "the model ran on the capture as it stands: the same rows ($c)" '[ "$(grep -vc "^#" "$work/cc-$c/measured.csv")" = "$(grep -vc "^#" "$work/cc-$c/simulated.csv")" ]'
  expect "the capture starts with the sequence: rpm_cmd 300 from t = 0 ($c)" 'grep -v "^#" "$work/cc-$c/measured.csv" | sed -n 2p | grep -q "^0,.*,300,2,inf$"'
  expect "the model says it ran the board's core ($c)" 'grep -q "^# controller: board: the firmware core" "$work/cc-$c/simulated.csv"'
done
kill "$board" 2>/dev/null
wait "$board" 2>/dev/null
expect "capture-compare.sh captured the step to 520 rpm under the PI" 'awk -F, "!/^#/ && \$2 > 500 { n++ } END { exit !(n > 100) }" "$work/cc-pi/measured.csv"'

finish "lab scripts"
