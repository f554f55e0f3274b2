#!/usr/bin/env bash
# mcg-serial console under a closed loop, and when things go wrong, in a tmux pane against the
# emulated board: a designed PI loaded from the keys, an rpm_cmd typed at the console that the
# board's loop (and the model's) then holds; a key prompt left open while recording loses no
# sample; the board vanishing mid-recording leaves the console waiting for it, and every row the
# recording counted is in the CSV, which mcg-sim reads.
# Args: TOOL_DIR SOURCE_DIR; exit 125 = skipped (no tmux).
tools=$1
export PATH="$tools:$PATH"
command -v tmux > /dev/null || { echo "skipped: tmux missing"; exit 125; }
. "$(dirname "$0")/serial_lib.sh"
session=mcg-console-loop-$$
trap 'tmux -L "$session" kill-server 2> /dev/null; cleanup' EXIT
export XDG_RUNTIME_DIR=$work
cd "$work" || exit 1
keys() { tmux -L "$session" send-keys -t "$session" "$@"; }

mcg-design pi --pm 50 --zero 500 --plant '16.557/((s/65+1)*(s/950+1))' --loop --dt 0.001 > pi.ini
start_board ./ttyRIG
mcg-serial -p ./ttyRIG set duty 40
sleep 1
tmux -L "$session" new-session -d -s "$session" -x 140 -y 40 \
  "mcg-serial -p ./ttyRIG console --seconds 120 2> console.err; echo console-exit=\$?; sleep 60"
check "the console runs" shows "board: mode open"
# The rig was turning when the console started: the model starts at the first measured speed,
# so no spin-up from rest enters the residual (3.5 rpm RMS over the first seconds when it did;
# the count quantisation alone is under 1).
sleep 2
residual=$(pane | head -1 | sed -n 's/.* residual RMS \([0-9.]*\) rpm.*/\1/p')
check "the model starts as the console found the rig (residual RMS ${residual:-?} rpm)" \
  awk -v r="${residual:-999}" 'BEGIN { exit !(r < 2) }'

keys o p i . i n i Enter
check "o loads the design INI" shows "loaded pi.ini"
check "the board runs its PI" shows "board: mode pi"
check "with the loaded coefficients in the registers line" eval '! pane | grep -q "  b0 0  b1 0 "'
keys r 6 5 0 Enter
check "r sets rpm_cmd" shows "rpm_cmd = 650"
sleep 3
rpm=$(title_rpm)
model=$(title_model)
check "the board's loop holds the speed typed ($rpm rpm for 650)" \
  awk -v a="${rpm:-0}" 'BEGIN { exit !(a > 630 && a < 670) }'
check "the model, driven by the measured duty, follows ($model rpm)" \
  awk -v a="${model:-0}" 'BEGIN { exit !(a > 600 && a < 700) }'

keys w r e c . c s v Enter
check "w starts a recording" shows "REC rec.csv"
keys r 3
check "a key prompt opens" shows "> rpm_cmd = 3_"
title_t() { pane | head -1 | sed -n 's/.*   t \([0-9.]*\) s .*/\1/p'; }
t_open=$(title_t)
sleep 3
t_later=$(title_t)
check "the stream runs on behind the open prompt (t $t_open -> $t_later s)" \
  awk -v a="${t_open:-0}" -v b="${t_later:-0}" 'BEGIN { exit !(b - a > 2.5) }'
check "and the prompt is still open" shows "> rpm_cmd = 3_"
keys Escape
check "Escape cancels it" shows "cancelled"
sleep 1
# The recorded times advance by one stream period, row after row: no sample was lost while the
# prompt was open, and the title never counted a lost one.
check "the recording has no gap" eval "grep -v '^#' rec.csv | awk -F, 'NR > 2 && (\$1 - t < 0.0035 || \$1 - t > 0.0045) { bad++ } NR > 1 { t = \$1; n++ } END { exit !(n > 800 && bad == 0) }'"
check "and the console saw no lost sample" eval '! pane | head -1 | grep -q " lost "'

kill "$board_pid"
check "the board vanishing: the console says so and waits for it" shows "./ttyRIG: THE PORT VANISHED"
keys w
check "w ends the recording meanwhile" shows "recorded "
recorded=$(pane | tail -1 | sed -n 's/.*recorded \([0-9]*\) rows to rec.csv.*/\1/p')
check "every row it counted is in the CSV ($recorded)" test "$(rows rec.csv)" = "${recorded:-none}"
check "mcg-sim reads the recording unedited" eval 'mcg-sim --compare < rec.csv > compare.csv 2> compare.err'
keys q
check "q ends the console with status 0" shows "console-exit=0"
check "and the terminal is given back" eval '! pane | grep -qF "keys: r rpm_cmd"'
check "nothing on stderr" test ! -s console.err
finish
