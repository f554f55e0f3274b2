#!/usr/bin/env bash
# The main job on the built-in rig, as the report's workflow runs it: simulate the coupled
# step, measure the plant's frequency response and fit it, design the PI exactly, verify it
# on the nonlinear model, and diagnose a sim-to-real gap. Writes CSV, INI and PNG files to
# OUT_DIR (default: out/) and prints a one-screen summary.
# Usage: main-job.sh [BIN_DIR] [OUT_DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=$(cd "${1:-$root/build/src/tools}" && pwd)
out=${2:-$root/out}
export PATH="$bin:$PATH"
mkdir -p "$out"
cd "$out"

# 1. The report's coupled step: 12 V at 0.1 s, clutch engaged, generator open.
mcg-sweep step --level 12 --at 0.1 --duration 0.6 --clutch 2 | mcg-sim --encoder > step.csv
mcg-plot-gnuplot -y rpm,rpm_true --y2 i --title "Coupled 12 V step (built-in rig)" -o step.png < step.csv

# 2. The plant's frequency response from a chirp, and its two-pole fit (the report's Fig. 16-1).
mcg-sweep chirp --bias 6 --amp 2 --f0 0.5 --f1 200 --duration 20 --clutch 2 \
  | mcg-sim | mcg-sweep bode --in v --out omega > bode.csv
mcg-fit tf --poles 2 --delay bode.csv > plant.ini
mcg-plot-gnuplot --bode --title "Plant omega/v, coupled, open circuit" -o bode.png < bode.csv

# 3. A PI for 50 degrees of phase margin in the report's loop, Tustin at 1 ms, fixed point.
mcg-design pi --pm 50 --zero 500 --config plant.ini --loop --dt 0.001 > pi.ini

# 4. Verify on the nonlinear model, quantised like the firmware: 420 rpm, then 520 rpm.
mcg-sweep step --column rpm_cmd --level 420 --at 0.05 --then 520@1 --duration 2 --clutch 2 \
  | mcg-sim --config pi.ini > verify.csv
mcg-plot-gnuplot -y rpm,rpm_cmd --title "PI on the nonlinear model" -o verify.png < verify.csv

# 5. The sim-to-real gap: "measured" runs from a rig whose supply sags (a 2.4 ohm source), the
#    diagnosis told nothing about it.
mcg-sweep prbs --bias 6 --amp 3 --clock 0.05 --duration 8 --clutch 2 --seed 3 \
  | mcg-sim --encoder --adc --noise-i 0.003 --seed 3 --effect supply_sag:R_s_ohm=2.4 > gap-train.csv
mcg-sweep step --level 4 --at 0.2 --then 9@1.5,14@3,6@4.5 --duration 6 --clutch 2 \
  | mcg-sim --encoder --adc --noise-i 0.003 --seed 4 --effect supply_sag:R_s_ohm=2.4 > gap-validate.csv
mcg-fit gap --train gap-train.csv --validate gap-validate.csv > gap.csv 2> gap.txt

# The summary.
steady=$(awk -F, '!/^#/ && $1 != "t" { last = $0 } END { split(last, f, ","); print f[7] }' step.csv)
echo "mcg main job on the built-in rig: files in $out"
echo "  step.csv, step.png        coupled 12 V step: steady speed ${steady} rpm"
echo "  bode.csv, bode.png        plant frequency response (chirp 0.5-200 Hz)"
echo "  plant.ini                 fitted plant: $(sed -n 's/^tf = \([^;]*[^; ]\) *;.*/\1/p' plant.ini)"
echo "  pi.ini                    PI for 50 deg: $(sed -n 's/^difference_equation = \([^;]*[^; ]\) *;.*/\1/p' pi.ini)"
echo "  verify.csv, verify.png    the PI on the nonlinear model (420 -> 520 rpm)"
echo "  gap.csv, gap.txt          diagnosis: $(awk -F, '!/^#/ && n++ == 1 { print $1 }' gap.csv)"
sed -n '1,12{s/^./    &/;p}' gap.txt
