#!/usr/bin/env bash
# Controller swaps on a running rig, as a person makes them against the emulated board: a PI holds
# 500 rpm, a board PID is loaded from another shell while a capture streams, and from the console
# (tmux) while it records; each capture is checked sample by sample: the speed never leaves
# 500 +- 25 rpm and the duty never drops to 0. Two shells loading at once each commit their own
# set. A mode switch to pi with the gains zero is refused by the board, from the shell and from
# the console, and the rig does not move; nor does a duty typed while the PI owns it. Usage: test_serial_swap.sh TOOL_DIR SOURCE_DIR; exit 125 = skipped.
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }
command -v tmux > /dev/null || { echo "skipped: tmux missing"; exit 125; }
session=mcg-swap-$$
trap 'tmux -L "$session" kill-server 2> /dev/null; cleanup' EXIT
export XDG_RUNTIME_DIR=$work
cd "$work" || exit 1
keys() { tmux -L "$session" send-keys -t "$session" "$@"; }
S() { timeout 30 mcg-serial -p ./ttyRIG "$@"; }

mcg-design pi --pm 50 --zero 500 --plant '16.557/((s/65+1)*(s/950+1))' --loop --dt 0.001 > pi.ini
mcg-design pid --form board --pm 50 --wc 200 --dt 0.001 --loop > pid.ini
check "the PID is the board's form" eval 'grep -q "^mode = pid" pid.ini'

# held CSV LO HI: every sample of the capture after its first 16 ms (the rpm window filling)
# has 500 +- 25 rpm and a duty above 0; prints the range seen.
held() {
  grep -v '^#' "$1" | awk -F, -v lo=475 -v hi=525 '
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    $c["t"] < 0.016 { next }
    { n++; r = $c["rpm"]; d = $c["duty"]
      if (n == 1 || r < rmin) rmin = r; if (n == 1 || r > rmax) rmax = r
      if (n == 1 || d < dmin) dmin = d
      if (r == "nan" || r < lo || r > hi || d <= 0) bad++ }
    END { printf "  %d samples: rpm %s..%s, duty >= %s\n", n, rmin, rmax, dmin; exit !(n > 500 && bad == 0) }'
}

start_board ./ttyRIG || exit 1
check "the PI takes the rig to 500 rpm" eval 'S set rpm_cmd 500 && S load pi.ini > /dev/null'
sleep 3

# From another shell: a capture owns the port, load goes through it in the middle.
S stream --seconds 8 > shell.csv 2> shell.err &
spid=$!
wait_rows shell.csv 200
check "load of the PID from another shell" eval 'S load pid.ini > pid.loaded 2> pid.err'
check "the board runs the PID" eval 'S get mode > v && same v pid'
wait_bounded $spid 20
check "the capture ran to its end without loss" eval '[ "$status" = 0 ] && [ ! -s shell.err ]'
check "swap from the shell: 500 +- 25 rpm and duty > 0 in every sample" held shell.csv

# Two shells load at once through a streaming port: the owner lets one stage the controller's set
# at a time, so each load commits its own set whole (load checks the board runs it after the commit).
S stream --seconds 30 > two.csv 2> two.err &
spid=$!
wait_rows two.csv 100
loads() { local i; for i in 1 2 3 4; do S load "$1" > /dev/null 2>> "$1.err" || return 1; done; }
loads pi.ini & apid=$!
loads pid.ini & bpid=$!
wait $apid; astatus=$?
wait $bpid; bstatus=$?
check "two shells loading at once: 8 loads, each committed whole" eval '[ $astatus = 0 ] && [ $bstatus = 0 ] &&
  [ ! -s pi.ini.err ] && [ ! -s pid.ini.err ]' || cat pi.ini.err pid.ini.err
kill "$spid" 2> /dev/null
wait "$spid" 2> /dev/null

# Back to the PI the same way, then the gains zeroed in open loop: a PI without gains is refused.
check "back to the PI" eval 'S load pi.ini > /dev/null'
sleep 1
check "open loop keeps the duty" eval 'S set mode open && S get duty > duty.before && awk "{ exit !(\$1 > 0) }" duty.before'
check "gains zeroed in open loop" eval 'S set b0 0 && S set b1 0 && S set b2 0'
check "mode pi with every gain zero: refused by the board, one line naming why" eval '! S set mode pi 2> err &&
  same err "mcg-serial: error: ./ttyRIG: committing mode pi: refused (NO_GAINS): a closed-loop mode with every gain zero (write its gains first); nothing changed"'
S stream --seconds 1 > still.csv
check "and the rig does not move: still open loop at the same duty" eval 'S get mode > v && same v open &&
  grep -v "^#" still.csv | awk -F, -v d="$(cat duty.before)" "NR > 1 && (\$4 * 100 - d > 0.05 || d - \$4 * 100 > 0.05) { bad++ } END { exit bad > 0 }"'

# From the console, recording: the same swap, the same refusals.
check "the PI holds 500 rpm again" eval 'S load pi.ini > /dev/null'
sleep 3
tmux -L "$session" new-session -d -s "$session" -x 160 -y 40 \
  "mcg-serial -p ./ttyRIG console --seconds 120 2> console.err; echo console-exit=\$?; sleep 60"
check "the console runs the PI" shows "board: mode pi"
keys d 2 0 Enter
check "a duty typed in mode pi: the board's reason" shows "the controller owns duty in mode pi; set mode open first"
keys w r e c . c s v Enter
check "w starts a recording" shows "REC rec.csv"
sleep 1
keys o p i d . i n i Enter
check "o loads the PID" shows "loaded pid.ini"
check "the board runs the PID" shows "board: mode pid"
sleep 1.5
keys w
check "the recording ends" shows "recorded"
check "swap from the console: 500 +- 25 rpm and duty > 0 in every sample" held rec.csv
keys m o p e n Enter
check "m: mode open" shows "mode = open"
keys s b 0 Space 0 Enter
keys s b 1 Space 0 Enter
keys s b 2 Space 0 Enter
check "gains zeroed" shows "b2 = 0"
keys m p i Enter
check "m: pi without gains refused, the code named" shows "refused (NO_GAINS)"
check "the mode stays open" eval 'S get mode > v && same v open'
keys q
check "the console ends normally" shows "console-exit=0"
finish
