#!/usr/bin/env bash
# Designs load: P, PI and the board's PID form from mcg-design load with mcg-serial load onto the
# emulated board (mcg-sim --board, the firmware's own core) and hold the speed command there as
# mcg-sim's closed loop (the same core) predicts. Usage: test_design_load.sh TOOL_DIR SOURCE_DIR
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }

plant='16.557/((s/65+1)*(s/950+1))'
mcg-design p --pm 55 --dt 0.001 > "$work/p.ini"
mcg-design pi --pm 50 --zero 500 --plant "$plant" --loop --dt 0.001 > "$work/pi.ini"
mcg-design pid --form board --pm 50 --wc 150 --plant "$plant" --loop --dt 0.001 > "$work/pid.ini"
check "the board's PID form is the board's: mode pid in [fixed_point], a = 1 -1" eval \
  'grep -q "^mode = pid" "$work/pid.ini" && grep -q "^a = 1 -1 " "$work/pid.ini"'

tty=$work/ttyMCG
start_board "$tty" || exit 1
S() { timeout 30 mcg-serial -p "$tty" "$@"; }

# settled_rpm INI: the model's mean rpm over 1.5..2 s of a 420 rpm command from rest.
settled_rpm() {
  awk 'BEGIN { print "t,rpm_cmd"; for (k = 0; k <= 2000; k++) printf "%g,420\n", k * 0.001 }' |
    mcg-sim --config "$1" | awk -F, '/^#/ { next } /^t/ { for (i = 1; i <= NF; i++) c[$i] = i; next }
      $1 >= 1.5 { s += $c["rpm"]; n++ } END { printf "%.0f\n", s / n }'
}

for c in p pi pid; do
  check "load $c" eval 'S set mode open > /dev/null && S set duty 0 > /dev/null && S set clutch 2 > /dev/null &&
    S set rpm_cmd 420 > /dev/null && S load "$work/$c.ini" > "$work/$c.loaded" 2> "$work/$c.err"'
  check "the board runs $c after load" eval 'S get mode > "$work/v" && same "$work/v" "$c"'
  sleep 2
  model=$(settled_rpm "$work/$c.ini")
  # Three readings of the 16 ms window, 0.2 s apart: all within 8 rpm of the model's mean
  # (the reading's resolution is 1.83 rpm; the model's mean is over 0.5 s).
  for k in 1 2 3; do
    check "$c on the board holds the model's speed (model $model rpm)" eval 'S get rpm > "$work/rpm" &&
      awk -v b="$(cat "$work/rpm")" -v m="$model" "BEGIN { d = b - m; if (d < 0) d = -d; if (d > 8) { print \"  board \" b \" rpm\"; exit 1 } }"'
    sleep 0.2
  done
done
check "P leaves its steady error, PI and PID none" eval '[ "$(settled_rpm "$work/p.ini")" -lt 400 ] &&
  [ "$(settled_rpm "$work/pi.ini")" -ge 415 ] && [ "$(settled_rpm "$work/pid.ini")" -ge 415 ]'

S set mode open > /dev/null
finish
