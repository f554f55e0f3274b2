#!/usr/bin/env bash
# mcg-sim as a live filter: each output row comes out while its input row is the last one in
# (the writer of the pipe waits for it before sending the next), for the open and the closed
# loop; and a live run gives the same table as a whole-file run.
# Usage: test_sim_stream.sh TOOL_DIR SOURCE_DIR.
set -u
tool_dir=$1
export PATH="$tool_dir:$PATH" LC_ALL=C
source "$(dirname "$0")/lib.sh"
cd "$work" || exit 1

# Feeds header and rows one at a time to a coprocess mcg-sim; after each row, reads the
# output until that row's line is there (10 s without it: the filter held it back).
# Writes the whole output to $2. Usage: lockstep INPUT OUTPUT ARGS...
lockstep() {
  local input=$1 output=$2
  shift 2
  coproc SIM { exec mcg-sim "$@"; }
  local pid=$SIM_PID out_fd=${SIM[0]} in_fd=${SIM[1]}
  local line got rows=0 ok=1
  : >"$output"
  while IFS= read -r line; do
    printf '%s\n' "$line" >&"$in_fd"
    case $line in [0-9]*) ;; *) continue ;; esac
    rows=$((rows + 1))
    local seen=0
    while IFS= read -r -t 10 got <&"$out_fd"; do
      printf '%s\n' "$got" >>"$output"
      case $got in [0-9]*) seen=$((seen + 1)) ;; esac
      [ "$seen" -ge 1 ] && break
    done
    if [ "$seen" -lt 1 ]; then
      echo "row $rows: no output row within 10 s of its input"
      ok=0
      break
    fi
  done <"$input"
  exec {in_fd}>&-
  while IFS= read -r got <&"$out_fd"; do printf '%s\n' "$got" >>"$output"; done
  wait "$pid" || ok=0
  [ "$ok" = 1 ]
}

{
  echo "t,v,clutch,r_load"
  for k in $(seq 0 40); do echo "$(awk -v k="$k" 'BEGIN {printf "%.3f", k * 0.005}'),12,2,5.6"; done
} >open.csv
expect "open loop: one output row per input row, while the input waits" 'lockstep open.csv open.live'
mcg-sim <open.csv >open.whole
expect "open loop: the live table equals the whole-file table" 'cmp -s open.live open.whole'
expect "open loop: the speed rises" 'awk -F, '"'"'/^[0-9]/ {r = $6} END {exit !(r > 50)}'"'"' open.live'

{
  echo "t,rpm_cmd"
  for k in $(seq 0 30); do echo "$(awk -v k="$k" 'BEGIN {printf "%.3f", k * 0.002}'),300"; done
} >closed.csv
expect "closed loop: one output row per input row, while the input waits" 'lockstep closed.csv closed.live --encoder'
mcg-sim --encoder <closed.csv >closed.whole
expect "closed loop: the live table equals the whole-file table" 'cmp -s closed.live closed.whole'

# A bad row mid-stream: the rows before it are out, then the error.
printf 't,v\n0,1\n0.001,1\n0.001,1\n' | mcg-sim >bad.out 2>bad.err
status=$?
expect "bad row: exit 1" '[ "$status" = 1 ]'
expect "bad row: the two good rows are written" '[ "$(grep -c "^0" bad.out)" = 2 ]'
expect "bad row: the error names the line" 'grep -qx "mcg-sim: error: <stdin>:4: column '"'"'t'"'"': 0.001 does not increase (previous row: 0.001)" bad.err'

finish "sim stream"
