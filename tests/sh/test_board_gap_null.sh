#!/usr/bin/env bash
# No false alarm on the board's own data path: the emulated board runs exactly the model the
# tools are given (no withheld effect). Two runs are played from the board's RAM (open-loop duty
# steps with clutch and load changes; the same kind of profile under a designed PI), captured
# with mcg-serial stream, and mcg-fit gap must say `none`: on the captures as they are, and with
# more speed noise than their metadata states (2 rpm of Gaussian noise added to every rpm
# sample, estimated from the data).
# Usage: test_board_gap_null.sh TOOL_DIR SOURCE_DIR
set -u
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }
command -v mcg-serial > /dev/null || { echo "mcg-serial not built, skipped"; exit 125; }

tty=$work/ttyMCG
start_board "$tty" --speed 4 || exit 1
S() { timeout 60 mcg-serial -p "$tty" "$@"; }

cat > "$work/open.csv" << 'CSV'
t,stream,duty,clutch,load
0,1,0.3,2,0
0.6,1,0.6,2,0
1.2,1,0.6,2,1
1.8,1,0.9,2,1
2.4,1,0.9,1,1
3,1,0.4,2,0
3.6,1,0.4,2,1
CSV
check "open-loop profile loaded" eval 'S send "$work/open.csv" > /dev/null'
check "run 1 captured without loss" eval 'S stream --seconds 4.2 --then play > "$work/run1.csv" 2> "$work/err" && [ ! -s "$work/err" ]'

mcg-design pi --pm 50 --zero 500 --plant '16.557/((s/65+1)*(s/950+1))' --loop --dt 0.001 > "$work/pi.ini"
check "the PI loads, then the board rests in open loop" eval 'S load "$work/pi.ini" > /dev/null &&
  S set mode open && S set duty 0 && S set rpm_cmd 300'
sleep 0.6
cat > "$work/pi_seq.csv" << 'CSV'
t,stream,mode,rpm_cmd,clutch,load
0,1,2,300,2,0
0.6,1,2,520,2,0
1.2,1,2,520,2,1
1.8,1,2,420,2,1
2.4,1,2,420,1,1
3,1,2,250,2,0
3.6,1,2,250,2,1
CSV
check "closed-loop profile loaded" eval 'S send "$work/pi_seq.csv" > /dev/null'
check "run 2 captured without loss" eval 'S stream --seconds 4.2 --then play > "$work/run2.csv" 2> "$work/err" && [ ! -s "$work/err" ]'
S set mode open > /dev/null

check "mcg-fit gap on the captures as they are: none" eval 'mcg-fit gap --train "$work/run1.csv" \
  --validate "$work/run2.csv" > "$work/gap.csv" 2> "$work/gap.err" && grep -qx "# diagnosis: none" "$work/gap.csv"'
grep "^# diagnosis\|^# reason" "$work/gap.csv"

# noisy FILE SEED: FILE with N(0, 2 rpm) added to its rpm column (the stated encoder's count is
# about 0.6 rpm of noise)
noisy() {
  awk -F, -v OFS=, -v seed="$2" 'BEGIN { srand(seed) } /^#/ { print; next }
    !h { for (k = 1; k <= NF; ++k) if ($k == "rpm") c = k; h = 1; print; next }
    { if ($c != "nan") { u = rand(); if (u < 1e-12) u = 1e-12; $c = $c + 2 * sqrt(-2 * log(u)) * cos(6.283185307 * rand()) }
      print }' "$1"
}
noisy "$work/run1.csv" 1 > "$work/noisy1.csv"
noisy "$work/run2.csv" 2 > "$work/noisy2.csv"
check "mcg-fit gap with more noise than the metadata states: none" eval 'mcg-fit gap --train "$work/noisy1.csv" \
  --validate "$work/noisy2.csv" > "$work/gap2.csv" 2> "$work/gap2.err" && grep -qx "# diagnosis: none" "$work/gap2.csv"'
grep "^# diagnosis\|^# reason\|^# noise" "$work/gap2.csv"
finish board_gap_null
