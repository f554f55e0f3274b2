#!/usr/bin/env bash
# The port shared as one, as a person uses it against the emulated board: the board announces
# its link and `list` shows it; an owner that ends normally while a client streams and a
# console (in tmux) records leaves both running, without a lost or repeated sample; pressing
# w never shows a stall; full gets meanwhile cost the streams no block; the board killed and
# started again on the same path is a break row in stream --reconnect's capture and in the
# console's recording; the console's keys ?, p, L.
# Args: TOOL_DIR SOURCE_DIR; exit 125 = skipped (no tmux).
tools=$1
export PATH="$tools:$PATH"
command -v tmux > /dev/null || { echo "skipped: tmux missing"; exit 125; }
. "$(dirname "$0")/serial_lib.sh"
session=mcg-shared-$$
trap 'tmux -L "$session" kill-server 2> /dev/null; cleanup' EXIT
export XDG_RUNTIME_DIR=$work
cd "$work" || exit 1

# steady FILE: every row measured, t in exact 4 ms steps (nothing lost, nothing twice).
steady() {
  grep -v '^#' "$1" | awk -F, 'NR == 1 { next }
    { n++; if ($4 == "nan") { print "  nan row at t = " $1; bad = 1 }
      if (n > 1 && ($1 - t < 0.0039 || $1 - t > 0.0041)) { print "  step " $1 - t " at t = " $1; bad = 1 }
      t = $1 }
    END { if (n < 100) { print "  only " n " rows"; bad = 1 }; exit bad }'
}
# one_break FILE: exactly one row of nan, and t jumps by more than 1.5 s across it.
one_break() {
  grep -v '^#' "$1" | awk -F, 'NR == 1 { next }
    $4 == "nan" { nan++; at = NR; before = t }
    NR == at + 1 && nan { jump = $1 - before }
    { if (NR > 2 && $1 <= t) bad = 1; t = $1 }
    END { if (nan != 1 || jump < 1.5 || bad) { print "  nan rows " nan ", jump " jump " s, t not increasing " bad + 0; exit 1 } }'
}

start_board ./ttyH
check "the board announces its link in one line" eval 'for i in $(seq 50); do [ -s board.err ] && break; sleep 0.1; done
  grep -Eqx "mcg-sim: board at ./ttyH \(/dev/pts/[0-9]+\); Ctrl-C ends" board.err'
check "mcg-serial list shows the emulated board" eval 'mcg-serial list | grep -Eq "^$work/ttyH	emulated board \(mcg-sim pid [0-9]+, /dev/pts/[0-9]+\)$"'

mcg-serial -p ./ttyH get > get0.ini
mcg-serial -p ./ttyH stream --seconds 6 > owner.csv 2> owner.err &
opid=$!
wait_rows owner.csv 10
mcg-serial -p ./ttyH stream --seconds 12 > client.csv 2> client.err &
cpid=$!
tmux -L "$session" new-session -d -s "$session" -x 140 -y 40 \
  "mcg-serial -p ./ttyH console --seconds 300 2> console.err; echo console-exit=\$?; sleep 60"
check "the console runs through the owner" shows "board: mode open"
tmux -L "$session" send-keys -t "$session" w r e c . c s v Enter
for i in $(seq 15); do pane | head -1; pane | tail -1; sleep 0.2; done > screens.txt
check "w starts a recording" shows "REC rec.csv"
check "w shows no stall in 3 s of screens" eval '! grep -q "no stream data" screens.txt'
check "and the console's time goes on meanwhile" eval 'grep -o "t [0-9.]* s" screens.txt | awk "{ print \$2 }" |
  sort -g | awk "NR == 1 { a = \$1 } END { exit !(\$1 - a > 2) }"'
for i in 1 2 3; do mcg-serial -p ./ttyH get > get$i.ini 2> get.err || echo "get $i: status $?" >> get.err; done
check "three full gets back to back while two streams run" eval '[ ! -s get.err ] && [ "$(grep -c " = " get3.ini)" -ge 27 ] &&
  [ "$(grep -c " = " get3.ini)" = "$(grep -c " = " get1.ini)" ]'
check "and the board dropped no block for them" eval 'grep -q "^tx_drops = 0 " get3.ini'
# settings: the registers only a write changes, as `get` prints them (stream aside: it is on now).
settings() { grep -Ev '^(;|\[|stream |duty |seq_state |tx_drops )' "$1"; }
check "the settings the owner answered from what it holds are the board's" eval 'diff <(settings get0.ini) <(settings get3.ini) &&
  [ "$(settings get3.ini | wc -l)" -ge 24 ]'
mcg-serial -p ./ttyH set rpm_cmd 515 > /dev/null
mcg-serial -p ./ttyH set kp 7 > /dev/null
mcg-serial -p ./ttyH get > get4.ini
check "a full get right after two sets shows both (a write forgets what it changes)" eval \
  'grep -q "^rpm_cmd = 515 " get4.ini && grep -q "^kp = 7 " get4.ini'
mcg-serial -p ./ttyH set rpm_cmd 420 > /dev/null
mcg-serial -p ./ttyH set kp 0 > /dev/null
sleep 2
check "the owner's own stream ended, it serves its clients still" eval '[ "$(rows owner.csv)" = 1500 ] && kill -0 $opid'
check "the client stream: 12 s, every sample once, status 0" eval 'wait_bounded $cpid 30 && [ "$status" = 0 ] &&
  [ "$(rows client.csv)" = 3000 ] && steady client.csv && [ ! -s client.err ]'
check "the console carries on" shows "REC rec.csv"
tmux -L "$session" send-keys -t "$session" w
check "w again stops the recording" shows "recorded "
check "the recording: every sample once across the owner's end" steady rec.csv
check "the owner has gone on serving the console" eval 'kill -0 $opid'

# The console's keys.
tmux -L "$session" send-keys -t "$session" '?'
check "? shows the keys" shows "keys (? closes this list):"
tmux -L "$session" send-keys -t "$session" '?'
check "? again hides them" shows "residual, rpm: x measured - model"
tmux -L "$session" send-keys -t "$session" p
check "p pauses the view" shows "PAUSED"
t1=$(pane | head -1 | sed -n 's/.* t \([0-9.]*\) s.*/\1/p')
sleep 1
t2=$(pane | head -1 | sed -n 's/.* t \([0-9.]*\) s.*/\1/p')
check "and the view stands still ($t1 s, then $t2 s)" test -n "$t1" -a "$t1" = "$t2"
tmux -L "$session" send-keys -t "$session" p
check "p again resumes it" shows "view resumed"
tmux -L "$session" send-keys -t "$session" L s e s s i o n . l o g Enter
check "L starts a session log" shows "session log to session.log"
tmux -L "$session" send-keys -t "$session" r 4 5 0 Enter
check "the board takes a value typed meanwhile" shows "rpm_cmd = 450"
tmux -L "$session" send-keys -t "$session" L
check "L again closes the log" shows "session log closed"
check "the log has the key with its UTC time" eval \
  'grep -Eq "^20[0-9]{2}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}\.[0-9]{3}Z set rpm_cmd 450$" session.log'
check "and what the board answered" eval 'grep -q "Z rpm_cmd = 450$" session.log'

# The port comes back: the board killed and started again on the same path.
tmux -L "$session" send-keys -t "$session" w r e c 2 . c s v Enter
check "a second recording" shows "REC rec2.csv"
mcg-serial -p ./ttyH stream --reconnect --allow-loss --seconds 10 > re.csv 2> re.err &
rpid=$!
wait_rows re.csv 100
kill "$board_pid"
wait "$board_pid" 2> /dev/null
check "the console says the port vanished" shows "THE PORT VANISHED"
check "the first owner ends with its port" eval 'wait_bounded $opid 10 && [ "$status" = 0 ]'
sleep 2
start_board ./ttyH
for i in $(seq 300); do grep -q "samples (" re.err && break; sleep 0.1; done
check "stream --reconnect goes on to its 10 s" eval '[ "$(rows re.csv)" = 2500 ]'
check "its capture marks the gap with one row of nan" one_break re.csv
check "and stderr says so" eval 'grep -Eq "^mcg-serial: note: ./ttyH: the port vanished; back after [0-9.]+ s, the gap is a row of nan in the capture$" re.err'
back() { ! pane | head -1 | grep -Eq "VANISHED|PORT BACK"; }
check "the console's data come back" eval 'for i in $(seq 100); do back && break; sleep 0.1; done; back'
sleep 1
tmux -L "$session" send-keys -t "$session" w
check "the second recording stops" shows "recorded "
check "it marks the gap with one row of nan" one_break rec2.csv
tmux -L "$session" send-keys -t "$session" q
check "q ends the console with status 0" shows "console-exit=0"
check "and the stream, which owned the port since it came back, ends with status 0" eval \
  'wait_bounded $rpid 10 && [ "$status" = 0 ]'
check "nothing on the console's stderr" test ! -s console.err
finish
