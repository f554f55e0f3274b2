#!/usr/bin/env bash
# mcg-serial console as a person uses it: in a tmux pane against the emulated board, keys
# sent with send-keys and the screen read with capture-pane. A duty typed at the console
# drives the speed and the model follows it; another mcg-serial writes through the console
# (the port owner) while it runs; a refused value shows in the status line; a recording
# started and stopped from the keys is a capture mcg-sim reads; q restores the terminal.
# Args: TOOL_DIR SOURCE_DIR; exit 125 = skipped (no tmux).
tools=$1
export PATH="$tools:$PATH"
command -v tmux > /dev/null || { echo "skipped: tmux missing"; exit 125; }
. "$(dirname "$0")/serial_lib.sh"
session=mcg-console-$$
trap 'tmux -L "$session" kill-server 2> /dev/null; cleanup' EXIT
export XDG_RUNTIME_DIR=$work
cd "$work" || exit 1

start_board ./ttyRIG
tmux -L "$session" new-session -d -s "$session" -x 140 -y 40 \
  "mcg-serial -p ./ttyRIG console --seconds 120 2> console.err; echo console-exit=\$?; sleep 60"

check "the console draws the stream and the registers" shows "board: mode open"
tmux -L "$session" send-keys -t "$session" d
check "d asks for the duty" shows "> duty (%) = _"
tmux -L "$session" send-keys -t "$session" 3 5 Enter
check "the board takes the duty" shows "duty = 35"
sleep 2
rpm=$(title_rpm)
model=$(title_model)
check "the speed follows the duty typed ($rpm rpm)" test "${rpm:-0}" -gt 800
check "the model follows it too ($model rpm, measured $rpm)" \
  awk -v a="${model:-0}" -v b="${rpm:-0}" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d < 0.1 * b) }'

check "another mcg-serial writes through the console" mcg-serial -p ./ttyRIG set rpm_cmd 500
check "and the console shows what it wrote" shows "rpm_cmd 500"

tmux -L "$session" send-keys -t "$session" r 9 9 9 9 Enter
check "a refused value shows in the status line" shows "refused: rpm_cmd: 9999 rpm is outside 120..720 rpm"

tmux -L "$session" send-keys -t "$session" w
tmux -L "$session" send-keys -t "$session" r e c . c s v Enter
check "w starts a recording" shows "REC rec.csv"
sleep 1.5
tmux -L "$session" send-keys -t "$session" w
check "w again stops it" shows "recorded "
check "the recording is a capture of more than 200 rows" test "$(rows rec.csv)" -gt 200
check "the recording starts at t = 0" eval '[ "$(grep -v "^#" rec.csv | awk -F, "NR == 2 { print \$1 }")" = 0 ]'
check "its metadata states the wall clock of its start" grep -Eq \
  '^# t0: the first row streamed after the recording began at [0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9:.]{12}Z' rec.csv
check "mcg-sim reads the recording unedited" eval 'mcg-sim --compare < rec.csv > compare.csv 2> compare.err'
check "with the speed measured beside the model's" eval 'grep -v "^#" compare.csv | head -1 | grep -q rpm_measured'

tmux -L "$session" send-keys -t "$session" q
check "q ends the console with status 0" shows "console-exit=0"
check "and gives the terminal back (no console screen left)" eval '! pane | grep -qF "keys: r rpm_cmd"'
check "nothing on stderr" test ! -s console.err
finish
