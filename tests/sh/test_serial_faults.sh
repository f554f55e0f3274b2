#!/usr/bin/env bash
# Fault tests: a relay between mcg-serial and the emulated board corrupts, drops and delays
# bytes, or cuts the line mid-stream. The tool resynchronises or reports in one line, never
# hangs, and keeps what it captured. Usage: test_serial_faults.sh TOOL_DIR SOURCE_DIR
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }

tty=$work/ttyMCG
start_board "$tty" || exit 1
timeout 30 mcg-serial -p "$tty" set clutch 2 || exit 1
timeout 30 mcg-serial -p "$tty" set duty 30 || exit 1

# start_relay LINK [relay options]: a faulty line from the board to LINK.
start_relay() {
  local link=$1
  shift
  timeout 300 mcg-serial -p "$tty" relay --link "$link" "$@" 2> "$work/relay.err" &
  relay_pid=$!
  bg_pids+=($relay_pid)
  wait_for "$link"
}
stop_relay() {
  kill "$relay_pid" 2> /dev/null
  wait_bounded "$relay_pid" 5
}
# t_increasing FILE: the t column strictly increases.
t_increasing() { grep -v '^#' "$1" | awk -F, 'NR > 2 && $1 <= t {bad = 1} {t = $1} END {exit bad}'; }

# 1. Light noise both ways: every request gets through (retries), the stream resynchronises.
noisy=$work/noisy
start_relay "$noisy" --corrupt 0.003 --drop 0.003 --stall 0.003 --stall-ms 40 --seed 5
N() { timeout 60 mcg-serial -p "$noisy" "$@"; }
ok=1
for v in 300 350 400 450 500 550 600 650; do
  N set rpm_cmd $v 2> "$work/err" || { cat "$work/err"; ok=0; }
  [ "$(N get rpm_cmd 2> "$work/err")" = $v ] || { cat "$work/err"; ok=0; }
done
check "noisy line: 8 set/get pairs all verified" [ $ok = 1 ]
N stream --seconds 4 --allow-loss > "$work/noisy.csv" 2> "$work/noisy.err"
status=$?
check "noisy line: stream --allow-loss exits 0" eval '[ $status = 0 ] || cat "$work/noisy.err"'
check "noisy line: 1000 samples (4 s of 4 ms) captured" [ "$(rows "$work/noisy.csv")" = 1000 ]
check "noisy line: t strictly increasing through the gaps" t_increasing "$work/noisy.csv"
check "noisy line: losses reported in one line, or none" eval '[ ! -s "$work/noisy.err" ] ||
  { [ "$(wc -l < "$work/noisy.err")" = 1 ] && grep -Eq "^mcg-serial: lost [0-9]+ of [0-9]+ samples" "$work/noisy.err"; }'
N stream --seconds 3 > "$work/strict.csv" 2> "$work/strict.err"
status=$?
check "noisy line: without --allow-loss, exit 3 exactly when samples were lost" eval '
  { [ $status = 3 ] && grep -q "^mcg-serial: lost" "$work/strict.err"; } || { [ $status = 0 ] && [ ! -s "$work/strict.err" ]; }'
stop_relay
check "the relay counted the damage it did" grep -Eq "corrupted.*dropped.*paused" "$work/relay.err"

# 2. Pauses inside frames (longer than the board's 20 ms frame timeout): the board drops the
#    truncated frames and says so, the host sends again.
stall=$work/stall
start_relay "$stall" --stall 0.03 --stall-ms 60 --seed 11
ok=1
for v in 410 420 430 440; do
  timeout 60 mcg-serial -p "$stall" set rpm_cmd $v 2> "$work/err" || { cat "$work/err"; ok=0; }
done
check "stalling line: every write verified" [ $ok = 1 ]
check "stalling line: the last value is held" eval '[ "$(timeout 60 mcg-serial -p "$stall" get rpm_cmd)" = 440 ]'
stop_relay

# 3. A line so bad that little gets through: the tool ends with one line, never hangs.
bad=$work/bad
start_relay "$bad" --corrupt 0.3 --drop 0.2 --seed 3
timeout 60 mcg-serial -p "$bad" --timeout 0.1 get rpm > "$work/out" 2> "$work/err"
status=$?
check "hopeless line: no hang" [ $status != 124 ]
check "hopeless line: a value, or one error line" eval '{ [ $status = 0 ] && [ -s "$work/out" ]; } ||
  { [ $status = 1 ] && [ "$(wc -l < "$work/err")" = 1 ] && grep -q "^mcg-serial: error: $bad: nothing answers" "$work/err"; }'
timeout 60 mcg-serial -p "$bad" --timeout 0.1 stream --seconds 1 > "$work/bad.csv" 2> "$work/err"
status=$?
check "hopeless line: stream ends, status 1 or 3" eval '[ $status = 1 ] || [ $status = 3 ]'
stop_relay

# 4. The line is cut mid-stream: the samples before the cut stay on stdout.
cut=$work/cut
start_relay "$cut" --cut-after 1.5
timeout 60 mcg-serial -p "$cut" stream > "$work/cut.csv" 2> "$work/cut.err"
status=$?
n=$(rows "$work/cut.csv")
check "cut line: stream ends with status 1" [ $status = 1 ]
check "cut line: one line naming the samples kept" \
  same "$work/cut.err" "mcg-serial: error: $cut: the port vanished after $n samples (they are on stdout)"
check "cut line: over a second of samples kept" [ "$n" -gt 250 ]
check "cut line: the last row is complete" eval 'tail -1 "$work/cut.csv" | grep -Eq "^[0-9.]+,[-0-9.na]+,[-0-9.na]+,[-0-9.]+,[-0-9.]+,[0-9na]+,[12],([0-9.]+|inf)$"'
wait_bounded "$relay_pid" 5
check "cut line: the relay says so" grep -q "^mcg-serial relay: line cut" "$work/relay.err"
check "the board still answers directly" eval '[ "$(timeout 30 mcg-serial -p "$tty" get rpm_cmd)" = 440 ]'
finish
