#!/usr/bin/env bash
# Excitations the board plays (exc_* registers), captured from their first tick: on the emulated
# board (the firmware's C core), a PRBS of order 5 with one bit per 4 ms stream sample is started
# by `stream --then excite`. Every row's duty must be the bit the LFSR definition gives (a Galois
# register, mask 0x14, seeded with 1, computed here in awk), from row 0 on: t = 0 is the
# excitation's first tick and no sample straddles a level change. The capture states the
# excitation in its metadata, and mcg-fit tf fits it as it is. A chirp the board plays is captured
# the same way, and mcg-sweep bode and mcg-fit tf read its column and band from that metadata.
# Usage: test_board_excite.sh TOOL_DIR SOURCE_DIR
tools=$1
source "$(dirname "$0")/serial_lib.sh"
export PATH="$tools:$PATH"
command -v mcg-sim > /dev/null || { echo "mcg-sim not built, skipped"; exit 125; }

tty=$work/ttyMCG
start_board "$tty" --speed 4 || exit 1
S() { timeout 60 mcg-serial -p "$tty" "$@"; }

check "a duty PRBS set: order 5, 4 ms per bit, 0.4 +- 0.2, two periods" eval 'S set clutch 2 && S set load 0 &&
  S set exc_kind prbs && S set exc_order 5 && S set exc_div 4 && S set exc_amp 200 && S set exc_offset 400 &&
  S set exc_periods 2'
check "the kind reads back by name" eval '[ "$(S get exc_kind)" = prbs ]'
check "captured from the excitation's start" eval 'S stream --samples 62 --then excite > "$work/prbs.csv" \
  2> "$work/err" && [ ! -s "$work/err" ]'
check "the capture states the excitation" grep -qx \
  '# excitation: prbs column=duty order=5 clock=0.004 amp=0.2 bias=0.4 periods=2' "$work/prbs.csv"
check "the capture states its time base" grep -q '^# t0: the excitation' "$work/prbs.csv"
awk 'function xor5(a, m,  r, k) { r = 0; for (k = 1; k < 32; k *= 2) if ((int(a / k) + int(m / k)) % 2) r += k
    return r }
  BEGIN { s = 1; for (k = 0; k < 62; k++) { if (k % 31 == 0) s = 1; b = s % 2; s = int(s / 2)
    if (b) s = xor5(s, 20); print (b ? 0.6 : 0.2) } }' > "$work/want"
grep -v '^#' "$work/prbs.csv" | awk -F, 'NR > 1 { print $4 + 0 }' > "$work/got"
check "every row's duty is the LFSR's bit, from t = 0" cmp -s "$work/want" "$work/got"
check "t starts at 0" eval '[ "$(grep -v "^#" "$work/prbs.csv" | awk -F, "NR == 2 { print \$1 }")" = 0 ]'
check "the excitation ended: exc_run reads 0" eval '[ "$(S get exc_run)" = 0 ]'

# A longer PRBS (order 7, 8 ms per bit, one period 1.016 s) fitted as captured.
check "a second PRBS set" eval 'S set exc_order 7 && S set exc_div 8 && S set exc_periods 1'
sleep 0.5
check "captured" eval 'S stream --samples 254 --then excite > "$work/prbs7.csv" 2> "$work/err" && [ ! -s "$work/err" ]'
check "mcg-fit tf fits the capture unedited (fit > 80 %)" eval 'mcg-fit tf --poles 2 "$work/prbs7.csv" \
  > "$work/plant.ini" 2> "$work/fit.err" &&
  awk -F" *= *" "/^fit_percent/ { exit !(\$2 + 0 > 80) }" "$work/plant.ini"'

# A chirp on the duty: 0.5 -> 20 Hz over 2 s, 0.4 +- 0.2, a level every tick.
check "a chirp set" eval 'S set exc_kind chirp && S set exc_f0 0.5 && S set exc_f1 20 && S set exc_sweep 2 &&
  S set exc_div 1 && S set exc_periods 1'
check "its frequencies read back in Hz" eval '[ "$(S get exc_f0)" = 0.5 ] && [ "$(S get exc_f1)" = 20 ]'
check "a chirp above half the level rate is refused" eval '! S set exc_div 30 2> /dev/null ||
  { ! S stream --samples 10 --then excite > /dev/null 2>&1; }'
check "exc_div back to one tick" S set exc_div 1
check "captured from its start" eval 'S stream --samples 500 --then excite > "$work/chirp.csv" 2> "$work/err" &&
  [ ! -s "$work/err" ]'
check "the capture states the chirp" grep -qx \
  '# excitation: chirp column=duty f0=0.5 f1=20 sweep=2 update=0.001 amp=0.2 bias=0.4 periods=1' "$work/chirp.csv"
check "the duty starts at the bias and swings over +- 0.2" eval 'grep -v "^#" "$work/chirp.csv" | awk -F, "
  NR == 2 { first = \$4 } NR > 1 { if (min == \"\" || \$4 < min) min = \$4; if (\$4 > max) max = \$4 }
  END { exit !(first > 0.39 && first < 0.43 && min >= 0.2 && min < 0.21 && max <= 0.6 && max > 0.59) }"'
check "mcg-sweep bode reads column and band from the capture" eval 'mcg-sweep bode "$work/chirp.csv" \
  > "$work/chirp-bode.csv" 2> /dev/null && grep -qx "# response: duty -> rpm" "$work/chirp-bode.csv" &&
  grep -v "^#" "$work/chirp-bode.csv" | awk -F, "NR > 1 { n++; if (\$1 < 0.5 || \$1 > 20) bad++ }
  END { exit !(n > 5 && bad == 0) }"'
check "mcg-fit tf fits duty -> rpm from the capture" eval 'mcg-fit tf --poles 2 "$work/chirp.csv" \
  > "$work/chirp.ini" 2> /dev/null && grep -q "^maps = duty -> rpm" "$work/chirp.ini" &&
  awk -F" *= *" "/^fit_percent/ { exit !(\$2 + 0 > 80) }" "$work/chirp.ini"'
finish
