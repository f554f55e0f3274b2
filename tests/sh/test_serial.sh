#!/usr/bin/env bash
# End-to-end: every mcg-serial subcommand against the emulated board (mcg-sim --board) through
# real pseudo-terminals; the clear errors (range, read-only, busy, nothing answering, the port
# vanishing mid-stream). Usage: test_serial.sh TOOL_DIR SOURCE_DIR
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }

tty=$work/ttyMCG
start_board "$tty" || exit 1
S() { timeout 30 mcg-serial -p "$tty" "$@"; }

check "list: one port per line, path and description" eval 'timeout 30 mcg-serial list > "$work/ports" &&
  ! grep -v "^/[^	]*	." "$work/ports"'
check "list: the emulated board among them" eval 'grep -q "^$tty	emulated board (mcg-sim pid [0-9]*, /dev/pts/[0-9]*)$" "$work/ports"'

# get / set / read-back
check "get prints the default speed command" eval 'S get rpm_cmd > "$work/out" && same "$work/out" 420'
check "set then get" eval 'S set rpm_cmd 500 && S get rpm_cmd > "$work/out" && same "$work/out" 500'
check "set a mode by name" eval 'S set mode open && S get mode > "$work/out" && same "$work/out" open'
check "set out of range is refused before sending" eval '! S set rpm_cmd 800 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: rpm_cmd: 800 rpm is outside 120..720 rpm"'
check "set a read-only register" eval '! S set rpm 10 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: set: rpm is read-only"'
check "set says when the board holds a rounded value" eval 'S set duty 12.34 2> "$work/err" &&
  same "$work/err" "mcg-serial: note: duty: 12.34 is held as 12.3 (the register'"'"'s resolution)"'
check "the board refuses a duty above duty_max" eval 'S set duty_max 50 && ! S set duty 60 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: $tty: writing duty: value outside the register'"'"'s range"'
check "duty_max back to 100" S set duty_max 100

# get (all) and load round trip
check "get writes a [board] section" eval 'S get > "$work/board.ini" && grep -qx "\[board\]" "$work/board.ini" &&
  grep -q "^rpm_cmd = 500 " "$work/board.ini"'
check "load reads get back" eval 'S set rpm_cmd 300 && S load "$work/board.ini" > "$work/out" &&
  S get rpm_cmd > "$work/v" && same "$work/v" 500'
cat > "$work/pi.ini" << 'INI'
[controller]
type = pi
b = 11.645 -6.987
a = 1 -1
dt_s = 0.001
input_scale = 0.008533333333333333
duty_full_scale = 922
INI
check "load a [controller] PI: Q12 coefficients, mode pi" eval 'S load "$work/pi.ini" > "$work/out" 2> "$work/err" &&
  S get mode coef_frac b0 b1 > "$work/v" && same "$work/v" "$(printf "pi\n12\n3.157470703125\n-1.89453125")"'
check "load notes the rounding of each coefficient" grep -q "note: b0: 3.157" "$work/err"
cat > "$work/bad.ini" << 'INI'
[board]
rpm_cmd = 500
speed = 3
INI
check "load names the line of an unknown register" eval '! S load "$work/bad.ini" 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: $work/bad.ini:3: [board] speed: not a register of the board"'

# stream: closed loop on the PI just loaded, clutch engaged
check "clutch on, speed command 450" eval 'S set clutch 2 && S set rpm_cmd 450'
sleep 2
check "stream --samples 500: rows, header, no loss" eval 'S stream --samples 500 > "$work/live.csv" 2> "$work/err" &&
  [ "$(rows "$work/live.csv")" = 500 ] && grep -qx "t,rpm,counts,duty,v,rpm_cmd,clutch,r_load" "$work/live.csv" && [ ! -s "$work/err" ]'
check "stream: t runs in 4 ms steps from 0" eval '[ "$(grep -v "^#" "$work/live.csv" | awk -F, "NR==2{print \$1} END{print \$1}" | tr "\n" " ")" = "0 1.996 " ]'
check "stream: the columns of mcg-csv(5)" eval '[ "$(grep -v "^#" "$work/live.csv" | head -1)" = "t,rpm,counts,duty,v,rpm_cmd,clutch,r_load" ]'
check "stream: the PI holds the speed command" eval 'grep -v "^#" "$work/live.csv" | awk -F, "NR>20 && \$2!=\"nan\" {s+=\$2; n++} END {m=s/n; exit !(m>440 && m<460)}"'
check "stream: rpm_cmd, clutch and r_load are reported" eval 'tail -1 "$work/live.csv" | grep -q ",450,2,inf$"'
check "stream --seconds 0.256 gives 64 samples" eval 'S stream --seconds 0.256 > "$work/s.csv" && [ "$(rows "$work/s.csv")" = 64 ]'
# The emulator stalled by the scheduler inside a frame: the host must not see a partial frame.
(for i in $(seq 10); do sleep 0.13; kill -STOP "$board_pid"; sleep 0.15; kill -CONT "$board_pid"; done) &
stall_pid=$!
check "a stalled emulator loses no sample" eval 'S stream --samples 400 > "$work/stall.csv" 2> "$work/err" &&
  [ "$(rows "$work/stall.csv")" = 400 ] && [ ! -s "$work/err" ]'
wait "$stall_pid"
check "the stream is off again" eval 'S get stream > "$work/v" && same "$work/v" 0'

# Ctrl-C keeps what was captured and ends cleanly
# (mcg-serial itself in the background: a non-interactive shell's jobs ignore SIGINT, but the
# handler mcg-serial installs for the capture overrides that.)
mcg-serial -p "$tty" stream > "$work/int.csv" 2> "$work/int.err" &
spid=$!
wait_rows "$work/int.csv" 200
kill -INT $spid
check "SIGINT: stream ends within 5 s" wait_bounded $spid 5
check "SIGINT ends stream with status 0" eval '[ "$status" = 0 ] || { cat "$work/int.err"; false; }'
check "SIGINT: the rows captured are on stdout" eval '[ "$(rows "$work/int.csv")" -gt 200 ] && tail -c 1 "$work/int.csv" | od -c | grep -q "\\\\n"'

# a second tool on the same port (test_serial_owner.sh has the rest)
S stream --seconds 3 > "$work/busy.csv" 2>&1 &
spid=$!
wait_rows "$work/busy.csv" 0
check "while another mcg-serial streams, get works through it" eval 'S get rpm_cmd > "$work/out" &&
  same "$work/out" 450'
wait $spid

# dump: record the RAM log at 1 ms spacing, then read it
check "dump --record --interval 1: 255 points" eval 'S dump --record --interval 1 > "$work/ram.csv" && [ "$(rows "$work/ram.csv")" = 255 ]'
check "dump: t = (i + 1) interval" eval 'grep -v "^#" "$work/ram.csv" | awk -F, "NR==2{a=\$1} END{b=\$1} END{exit !(a==0.001 && b==0.255)}"'
check "dump: rpm = counts / 2048 / interval * 60" eval 'grep -v "^#" "$work/ram.csv" | awk -F, "NR>1 {d=\$2-\$3*60/2048/0.001; if (d>1e-6||d<-1e-6) bad=1} END{exit bad}"'
check "dump: the speed is held by the closed loop" eval 'grep -v "^#" "$work/ram.csv" | awk -F, "NR>1 {s+=\$2; n++} END {m=s/n; exit !(m>430 && m<470)}"'
check "dump metadata: sample_period" grep -qx "# sample_period: 0.001" "$work/ram.csv"

# send: a command sequence, played
printf 't,rpm_cmd,clutch\n0,400,2\n0.1,400,2\n0.3,520,2\n0.5,520,1\n' > "$work/seq.csv"
check "send --then play" eval 'S send "$work/seq.csv" --then play > "$work/out" &&
  same "$work/out" "sequence: 4 entries over 0.5 s loaded, playing"'
sleep 0.8
check "the sequence ran" eval 'S get rpm_cmd clutch seq_len > "$work/v" && same "$work/v" "$(printf "520\n1\n4")"'
# A playing sequence with a controller row owns the board's controller set until it stops.
printf 't,duty_bias,rpm_cmd\n0,0,420\n20,0,500\n' > "$work/owns.csv"
check "a sequence that changes the controller plays" eval 'S send "$work/owns.csv" --then play > /dev/null &&
  S get flags | grep -q "seq,seq_set$"'
check "set is refused while that sequence plays" eval '! S set kp 1.5 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: $tty: staging a controller: a playing sequence owns the controller'"'"'s set until it stops (seq_state 0); nothing was written"'
check "stopping the sequence frees the set" eval 'S set seq_state stop && S set kp 1.5 && S set rpm_cmd 520 &&
  S get kp > "$work/v" && same "$work/v" 1.5 && ! S get flags | grep -q seq'
printf 't,rpm_cmd\n0,400\n0.1,900\n' > "$work/bad.csv"
check "send names the row of a value out of range" eval '! S send "$work/bad.csv" 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: $work/bad.csv:3: rpm_cmd: 900 rpm is outside 120..720 rpm"'

# monitor: a terminal only
check "monitor refuses a pipe" eval '! S monitor --seconds 0.3 > "$work/out" 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: monitor: stdout is not a terminal (use '"'"'stream'"'"' to capture data)"'
if command -v script > /dev/null; then
  check "monitor redraws one line on a terminal" eval 'timeout 30 script -qec "mcg-serial -p $tty monitor --seconds 0.5" /dev/null > "$work/mon" &&
    grep -q "rpm .* cmd  520" "$work/mon" && [ "$(grep -c . "$work/mon")" = 1 ]'
fi

# the port vanishes mid-stream: what was captured stays
S set clutch 2 > /dev/null
S stream > "$work/gone.csv" 2> "$work/gone.err" &
spid=$!
wait_rows "$work/gone.csv" 400
kill "$board_pid"
wait $spid
status=$?
check "the board going away ends stream with status 1" [ "$status" = 1 ]
n=$(rows "$work/gone.csv")
check "the vanish message counts the samples kept on stdout" \
  same "$work/gone.err" "mcg-serial: error: $tty: the port vanished after $n samples (they are on stdout)"
check "the samples kept are many" [ "$n" -gt 300 ]
check "the board removed its link" eval '! [ -e "$tty" ]'
check "no such port (board gone)" eval '! S get rpm 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: $tty: no such port (the list command shows the serial ports)"'

# nothing answers: a pseudo-terminal pair with nobody on the far end
if command -v socat > /dev/null; then
  socat pty,raw,echo=0,link="$work/mute" pty,raw,echo=0,link="$work/mute_far" &
  bg_pids+=($!)
  wait_for "$work/mute"
  check "nothing answers" eval '! timeout 30 mcg-serial -p "$work/mute" --timeout 0.1 get rpm 2> "$work/err" &&
    same "$work/err" "mcg-serial: error: $work/mute: nothing answers the version request after 3 tries (board off, not connected, or not running the mcg firmware?)"'
fi
finish
