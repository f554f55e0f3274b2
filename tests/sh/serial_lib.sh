# Shared by the test_serial*.sh suites, over lib.sh: bounded waits, the emulated board, the
# console in tmux.
set -u
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

# wait_for PATH: waits up to 10 s for PATH to exist.
wait_for() {
  local i
  for i in $(seq 100); do
    [ -e "$1" ] && return 0
    sleep 0.1
  done
  echo "  $1 did not appear"
  return 1
}

# start_board LINK [mcg-sim options]: the emulated board in the background, ended at exit.
start_board() {
  local link=$1
  shift
  timeout 300 mcg-sim --board "$link" "$@" 2> "$work/board.err" &
  bg_pids+=($!)
  board_pid=$!
  wait_for "$link"
}

# wait_bounded PID SECONDS: waits for PID to end (its status in $status), killing it after
# SECONDS; returns 1 if it had to be killed.
wait_bounded() {
  local i
  for i in $(seq $(($2 * 10))); do
    if ! kill -0 "$1" 2> /dev/null; then
      wait "$1"
      status=$?
      return 0
    fi
    sleep 0.1
  done
  kill -KILL "$1" 2> /dev/null
  wait "$1"
  status=$?
  echo "  pid $1 had to be killed"
  return 1
}

# wait_rows FILE N: waits up to 20 s until the CSV FILE has more than N data rows.
wait_rows() {
  local i
  for i in $(seq 200); do
    [ -s "$1" ] && [ "$(rows "$1")" -gt "$2" ] && return 0
    sleep 0.1
  done
  echo "  $1 did not reach $2 rows"
  return 1
}

# rows FILE: data rows of a CSV (lines after the header, metadata excluded).
rows() { grep -v '^#' "$1" | tail -n +2 | grep -c .; }

# pane: the screen of the tmux session $session (the console suites).
pane() { tmux -L "$session" capture-pane -p -t "$session"; }

# shows TEXT: waits up to 10 s for TEXT on the screen of $session.
shows() {
  local i
  for i in $(seq 100); do
    pane | grep -qF -- "$1" && return 0
    sleep 0.1
  done
  echo "  the screen never showed '$1':"
  pane | sed 's/^/  | /' | grep -v '^  | *$' | tail -8
  return 1
}

# title_rpm, title_model: the measured and the model's speed in the console's title line.
title_rpm() { pane | head -1 | sed -n 's/.* rpm \([0-9-]*\) .*/\1/p'; }
title_model() { pane | head -1 | sed -n 's/.* model \([0-9-]*\) .*/\1/p'; }
