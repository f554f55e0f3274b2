#!/usr/bin/env bash
# mcg-serial against the 8051 SIM image running in s51 (ucsim), its UART bridged to a
# pseudo-terminal with socat: the version check, register writes and read-back, and the 8051
# firmware's own range refusal. Exit 125 (skipped) without sdcc, s51 or socat.
# Usage: test_serial_ucsim.sh TOOL_DIR SOURCE_DIR
tools=$1
src=$2
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
for tool in sdcc s51 socat make; do
  command -v $tool > /dev/null || { echo "$tool not found, skipped"; exit 125; }
done

make -s -C "$src/firmware" BUILD="$work/fw" "$work/fw/mcg-ucsim.ihx" > "$work/make.log" 2>&1 ||
  { cat "$work/make.log"; exit 1; }

# ucsim-notes §3: a socat pty pair; s51 gets one end with uart0_flowctrl=1 (else 0x18 opens its
# menu) and uart0_check_often=1 (else input trickles in); its stdin stays open (EOF ends s51).
socat pty,raw,echo=0,link="$work/ttySIM" pty,raw,echo=0,link="$work/ttyHOST" &
bg_pids+=($!)
wait_for "$work/ttySIM" && wait_for "$work/ttyHOST" || exit 1
mkfifo "$work/s51.in"
exec 3<> "$work/s51.in"
timeout -k 5 300 s51 -t C517 -X 12M -e 'expr uart0_check_often=1;expr uart0_flowctrl=1' -s "$work/ttySIM" -g \
  "$work/fw/mcg-ucsim.ihx" < "$work/s51.in" > "$work/s51.log" 2>&1 &
bg_pids+=($!)

U() { timeout 60 mcg-serial -p "$work/ttyHOST" --timeout 1 "$@"; }
# The simulator needs a moment to load the image and start.
for i in $(seq 50); do
  U get mode > /dev/null 2>&1 && break
  sleep 0.2
done
check "the SIM image answers with protocol 4 (version checked)" eval '[ "$(U get mode)" = open ]'
check "all registers read" eval 'U get > "$work/all.ini" && grep -q "^rpm_cmd = 420 " "$work/all.ini"'
check "set rpm_cmd, read back" eval 'U set rpm_cmd 555 && [ "$(U get rpm_cmd)" = 555 ]'
check "set a gain in Q8, read back" eval 'U set kp 2.75 && [ "$(U get kp)" = 2.75 ]'
check "the 8051 refuses a duty above duty_max" eval 'U set duty_max 50 && ! U set duty 60 2> "$work/err" &&
  same "$work/err" "mcg-serial: error: $work/ttyHOST: writing duty: value outside the register'"'"'s range"'
check "the refused write left duty unchanged" eval '[ "$(U get duty)" = 0 ]'
exec 3>&-
finish
