#!/usr/bin/env bash
# One owner of the port: while one mcg-serial streams (or serves), every other mcg-serial
# command on the port works through it with the answers and errors it gets alone; stream
# blocks go to each reader without loss; a dead owner's stale socket does not stand in the way.
# Usage: test_serial_owner.sh TOOL_DIR SOURCE_DIR
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }
export XDG_RUNTIME_DIR=$work

tty=$work/ttyMCG
start_board "$tty" || exit 1
S() { timeout 30 mcg-serial -p "$tty" "$@"; }
check "clutch on, speed command 450" eval 'S set clutch 1 && S set rpm_cmd 450'

# A stream owns the port until Ctrl-C; everything else goes through it (at 9600 baud the
# stream takes most of the line, so each request waits for its turn between blocks).
mcg-serial -p "$tty" stream --allow-loss > "$work/own.csv" 2> "$work/own.err" &
spid=$!
wait_rows "$work/own.csv" 10
check "the owner listens on its control socket" eval 'ls "$work"/mcg-serial.*.sock > /dev/null'
check "get through the owner" eval 'S get rpm_cmd > "$work/out" && same "$work/out" 450'
check "set through the owner, read back" eval 'S set rpm_cmd 500 && S get rpm_cmd > "$work/out" && same "$work/out" 500'
check "a refusal before sending, as alone" eval '! S set rpm_cmd 800 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: rpm_cmd: 800 rpm is outside 120..720 rpm"'
check "the board's refusal, as alone" eval 'S set duty_max 50 && ! S set duty 60 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: $tty: writing duty: value outside the register'"'"'s range" && S set duty_max 100'
check "get (all) through the owner" eval 'S get > "$work/board.ini" && grep -q "^rpm_cmd = 500 " "$work/board.ini"'
check "load through the owner" eval 'S set rpm_cmd 300 && S load "$work/board.ini" > /dev/null &&
  S get rpm_cmd > "$work/out" && same "$work/out" 500'
printf 't,rpm_cmd\n0,400\n0.2,460\n' > "$work/seq.csv"
check "send through the owner" eval 'S send "$work/seq.csv" > "$work/out" &&
  same "$work/out" "sequence: 2 entries over 0.2 s loaded" && S get seq_len > "$work/v" && same "$work/v" 2'
check "a second stream beside the owner's, no loss" eval 'S stream --samples 300 > "$work/two.csv" 2> "$work/two.err" &&
  [ "$(rows "$work/two.csv")" = 300 ] && [ ! -s "$work/two.err" ]'
check "the second stream ending leaves the stream on for the owner" eval 'S get stream > "$work/v" && same "$work/v" 1'
check "serve refuses while another mcg-serial holds the port" eval '! S serve --seconds 1 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: $tty: another mcg-serial holds the port and serves it already"'
# Many clients at once: each gets its own answers.
# Their requests queue behind each other between the stream's blocks: a longer --timeout.
for k in 1 2 3 4 5 6; do (for j in 1 2 3; do S --timeout 1 get rpm_cmd || echo FAILED; done > "$work/par$k") & done
wait_par() { for k in 1 2 3 4 5 6; do [ "$(grep -c 500 "$work/par$k")" = 3 ] || return 1; done; }
for i in $(seq 100); do wait_par && break; sleep 0.2; done
check "six clients at once, every answer right" wait_par
kill -INT $spid
check "the owner ends on Ctrl-C" wait_bounded $spid 10
# A stalled emulator (a loaded machine) can cost a block; mixed or misrouted frames cost many.
# The strict figure (no sample lost over 10 minutes) is bench_serial_soak's.
check "the owner's stream: under 1 % of the samples lost" eval '[ "$status" = 0 ] &&
  [ "$(rows "$work/own.csv")" -gt 1000 ] &&
  { [ ! -s "$work/own.err" ] || awk "/lost/ {exit !(\$3 * 100 < \$5)}" "$work/own.err"; }'
check "the stream is off after its owner ended" eval 'S get stream > "$work/v" && same "$work/v" 0'
check "the socket is gone with its owner" eval '! ls "$work"/mcg-serial.*.sock 2> /dev/null'

# The owner killed: its socket stays behind, the next command opens the port itself.
mcg-serial -p "$tty" serve > /dev/null 2>&1 &
opid=$!
for i in $(seq 50); do ls "$work"/mcg-serial.*.sock > /dev/null 2>&1 && break; sleep 0.1; done
check "serve: get through it" eval 'S get rpm_cmd > "$work/out" && same "$work/out" 500'
check "dump --record through the owner" eval 'S dump --record --interval 1 > "$work/ram.csv" && [ "$(rows "$work/ram.csv")" = 255 ]'
kill -KILL $opid
wait $opid 2> /dev/null
check "a stale socket after the owner's death" eval 'ls "$work"/mcg-serial.*.sock > /dev/null'
check "the next command opens the port itself" eval 'S get rpm_cmd > "$work/out" && same "$work/out" 500'
check "the next stream owns the port again" eval 'S stream --samples 50 > "$work/again.csv" && [ "$(rows "$work/again.csv")" = 50 ]'
finish
