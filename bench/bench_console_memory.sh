#!/usr/bin/env bash
# mcg-serial console's memory over a long run: the console in a tmux pane against the emulated
# board, recording the stream to a CSV all along while another mcg-serial writes rpm_cmd through
# it every 5 s; its resident memory (VmRSS) sampled every 10 s. Flat means: after the first
# minute (the trace span filled, the allocator warmed up) it grows by less than 1 MiB.
# Usage: bench_console_memory.sh TOOL_DIR SECONDS (a Release build; needs tmux).
set -euo pipefail
tools=$(cd "$1" && pwd)
seconds=$2
export PATH="$tools:$PATH"
command -v tmux >/dev/null || { echo "console memory: not measured (tmux missing)"; exit 0; }
work=$(mktemp -d)
session=mcg-bench-console-$$
board_pid=
writer_pid=
cleanup() {
  tmux -L "$session" kill-server 2>/dev/null || true
  [[ -n $writer_pid ]] && kill "$writer_pid" 2>/dev/null
  [[ -n $board_pid ]] && kill "$board_pid" 2>/dev/null
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
cd "$work"
export XDG_RUNTIME_DIR=$work

mcg-sim --board "$work/ttyRIG" 2>board.err &
board_pid=$!
for _ in $(seq 100); do [[ -e "$work/ttyRIG" ]] && break; sleep 0.1; done
tmux -L "$session" new-session -d -s "$session" -x 140 -y 40 \
  "mcg-serial -p $work/ttyRIG console --seconds $((seconds + 30)) 2>console.err; echo \$? >console.status"
pid=
for _ in $(seq 100); do
  pid=$(pgrep -f "^mcg-serial -p $work/ttyRIG console" | head -1 || true)
  [[ -n $pid ]] && break
  sleep 0.1
done
[[ -n $pid ]] || { echo "console memory: the console did not start"; exit 1; }
sleep 2
tmux -L "$session" send-keys -t "$session" w r e c . c s v Enter
( while :; do mcg-serial -p "$work/ttyRIG" set rpm_cmd $((200 + RANDOM % 400)) >/dev/null 2>>writes.err || echo fail >>writes.err; sleep 5; done ) &
writer_pid=$!

# The console itself (not the tmux server or the shell, whose command lines hold the same words).
rss() { awk '/^VmRSS:/ {print $2}' "/proc/$pid/status"; }
start=$(date +%s)
first=
max=0
last=0
while :; do
  now=$(date +%s)
  elapsed=$((now - start))
  kb=$(rss) || break
  ((kb > max)) && max=$kb
  [[ -z $first && $elapsed -ge 60 ]] && first=$kb
  last=$kb
  echo "$elapsed $kb" >>rss.txt
  ((elapsed >= seconds)) && break
  sleep 10
done
kill "$writer_pid" 2>/dev/null || true
wait "$writer_pid" 2>/dev/null || true
writer_pid=
screen=$(tmux -L "$session" capture-pane -p -t "$session" | head -1)
tmux -L "$session" send-keys -t "$session" w
sleep 1
tmux -L "$session" send-keys -t "$session" q
for _ in $(seq 100); do [[ -s console.status ]] && break; sleep 0.1; done
rows=$(grep -v '^#' rec.csv | tail -n +2 | grep -c . || true)
lost=$(sed -n 's/.*   lost \([0-9]*\).*/\1/p' <<<"$screen")
failed_writes=$(grep -c . writes.err 2>/dev/null || true)
first=${first:-$last}
echo "console memory: ${seconds} s of streaming (recording ${rows} rows, rpm_cmd written every 5 s," \
  "${failed_writes:-0} writes failed, ${lost:-0} samples lost): VmRSS ${first} KiB at 60 s," \
  "${last} KiB at the end, max ${max} KiB, growth after the first minute $((last - first)) KiB;" \
  "exit $(cat console.status 2>/dev/null || echo '?')"
