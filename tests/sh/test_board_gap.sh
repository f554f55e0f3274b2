#!/usr/bin/env bash
# The workstation loop on the board's own data path: the emulated board runs a plant with an
# effect the model does not have (supply sag, 2.5 ohm); two runs are played from the board's
# RAM (open-loop duty steps with clutch and load changes; the same kind of profile under a
# designed PI) and captured with mcg-serial stream; mcg-fit gap, on the captures as they are,
# names the effect and closes most of the gap. Then bad input on the same path: a capture
# with lost samples, the port vanishing mid-stream.
# Usage: test_board_gap.sh TOOL_DIR SOURCE_DIR
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }

tty=$work/ttyMCG
start_board "$tty" --effect supply_sag:R_s_ohm=2.5 --speed 4 || exit 1
S() { timeout 60 mcg-serial -p "$tty" "$@"; }

# Run 1: open loop. The sequence's first entry turns the stream on, so t = 0 is its start.
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
# A duty written by the sequence acts from the next 1 ms update: the first row's mean is 3/4 of it.
check "run 1: 1050 rows from t = 0, the profile's first duty from the first row on" eval '[ "$(rows "$work/run1.csv")" = 1050 ] &&
  grep -v "^#" "$work/run1.csv" | sed -n "2p;3p" | tr "\n" " " | grep -q "^0,nan,nan,0.225,4.5,[0-9]*,2,inf 0.004,nan,[0-9]*,0.3,6,"'
check "run 1: the clutch disengaged and the load closed where the profile says" eval '
  grep -v "^#" "$work/run1.csv" | grep -q "^2.4,.*,1,5.6$" && grep -v "^#" "$work/run1.csv" | grep -q "^2.396,.*,2,5.6$"'

# Run 2: the same kind of profile under a PI designed for 50 degrees.
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
check "run 2: the PI holds 520 rpm" eval 'grep -v "^#" "$work/run2.csv" | grep "^1\.[01][0-9]*," | cut -d, -f2 |
  sort -n | sed -n "1p;\$p" | tr "\n" " " | grep -Eq "^5(1[89]|2[0-2])\.[0-9]+ 5(1[89]|2[0-2])\.[0-9]+ $"'
S set mode open > /dev/null

# The diagnosis on the unedited captures.
check "mcg-fit gap runs on the captures as they are" eval 'mcg-fit gap --train "$work/run1.csv" --validate "$work/run2.csv" \
  > "$work/gap.csv" 2> "$work/gap.err"'
check "the diagnosis names the withheld effect" grep -qx "# diagnosis: supply_sag" "$work/gap.csv"
check "the effect closes most of the gap (validation RMS shrinks by more than 80 %)" eval '
  grep "^supply_sag," "$work/gap.csv" | cut -d, -f4 | grep -Eq "^(8[0-9]|9[0-9])(\.[0-9]+)?$"'
check "the fitted R_s is within 10 % of the withheld 2.5 ohm" eval '
  grep -o "supply_sag.R_s_ohm=[0-9.]*" "$work/gap.csv" | head -1 | grep -Eq "=2\.([3-6][0-9]*|2[5-9][0-9]*|7[0-4][0-9]*)$"'

# A capture with lost samples: a line that drops bytes towards the tool. The loss is one line
# on stderr and exit status 3; every row received is on stdout, the lost ones are rows of nan
# at their times; a tool driven by such a capture stops at the first lost row, naming it.
timeout 300 mcg-serial -p "$tty" relay --link "$work/ttyLOSSY" --drop 0.002 --clean-to-board --seed 3 \
  2> "$work/relay.err" &
relay_pid=$!
bg_pids+=($relay_pid)
wait_for "$work/ttyLOSSY"
check "lossy profile loaded" eval 'timeout 60 mcg-serial -p "$work/ttyLOSSY" send "$work/open.csv" > /dev/null'
timeout 60 mcg-serial -p "$work/ttyLOSSY" stream --seconds 4.2 --then play > "$work/lossy.csv" 2> "$work/lossy.err"
status=$?
kill "$relay_pid" 2> /dev/null
check "lost samples: exit status 3" [ "$status" = 3 ]
check "lost samples: one line that counts them" eval '[ "$(wc -l < "$work/lossy.err")" = 1 ] &&
  grep -Eq "^mcg-serial: lost [0-9]+ of 1050 samples" "$work/lossy.err"'
lost=$(sed -n 's/^mcg-serial: lost \([0-9]*\) of.*/\1/p' "$work/lossy.err")
check "lost samples: all 1050 rows are there, the lost ones as nan rows" eval '[ "$(rows "$work/lossy.csv")" = 1050 ] &&
  [ "$(grep -c "^[0-9.]*,nan,nan,nan,nan,nan,nan,nan$" "$work/lossy.csv")" = "${lost:-x}" ]'
first=$(grep -v '^#' "$work/lossy.csv" | grep -n "^[0-9.]*,nan,nan,nan,nan,nan,nan,nan$" | head -1 | cut -d: -f1)
line=$(( $(grep -c '^#' "$work/lossy.csv") + ${first:-0} ))
check "lost samples: mcg-fit gap names the first lost row" eval '! mcg-fit gap --train "$work/lossy.csv" --validate "$work/run2.csv" \
  > /dev/null 2> "$work/err" && same "$work/err" "mcg-fit: error: $work/lossy.csv:$line: column '"'"'v'"'"': an unmeasured value (nan or empty) is not allowed here"'
check "lost samples: mcg-sim replay stops there too" eval '! mcg-sim --open-loop < "$work/lossy.csv" > /dev/null 2> "$work/err" &&
  same "$work/err" "mcg-sim: error: <stdin>:$line: column '"'"'v'"'"': an unmeasured value (nan or empty) is not allowed here"'

# The port vanishes mid-stream: one line, status 1, every row captured stays complete.
S stream > "$work/gone.csv" 2> "$work/gone.err" &
spid=$!
wait_rows "$work/gone.csv" 200
kill "$board_pid"
wait_bounded $spid 10
check "the board going away ends stream with status 1" [ "$status" = 1 ]
n=$(rows "$work/gone.csv")
check "the vanish message is one line counting the rows kept" \
  same "$work/gone.err" "mcg-serial: error: $tty: the port vanished after $n samples (they are on stdout)"
check "every row kept is complete" eval 'grep -v "^#" "$work/gone.csv" | tail -n +2 | awk -F, "NF != 8 { bad = 1 } END { exit bad }"'

echo "board gap: $((checks - failures)) of $checks checks passed"
[ "$failures" = 0 ]
