#!/usr/bin/env bash
# bench-excite.sh [BUILD_DIR [CRC [CHIRP_CRC]]]: machine cycles the excitation generator (excite_tick)
# adds to the 1 ms tick, measured in s51 at 12 MHz (1 machine cycle = 1 us) on bench/bench_excite.c,
# and the CRC-16 of the duties a PRBS (order 9, exc_div 1, 400 +- 200) and a chirp (0.1 -> 50 Hz over
# 3 s, exc_div 1, 400 +- 300) play over 10 s each (the host core's figures are checked by
# tests/firmware/test_fw_excite.cpp). Goal: at most 250 cycles for a PRBS bit or a stair on a duty
# target, so that with the PID (at most 300) the update stays within half the 1000-cycle tick, and at
# most 600 for a chirp's level (a phase step, a table step and an exact frequency step, all 32-bit
# in external RAM), so that with the PID it stays within the tick; at most 700 for a PRBS bit on
# rpm_cmd in closed loop (the controller's R for each level is precomputed at the start), so that with
# the PID it stays within the tick. Exits 1 if a goal is missed or a CRC differs from CRC or
# CHIRP_CRC (given as 0xHHHH), 125 if sdcc or s51 is missing.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
want_crc=${2:-}
want_chirp=${3:-}
for tool in sdcc s51 timeout; do
  command -v "$tool" > /dev/null || { echo "bench-excite: $tool not found" >&2; exit 125; }
done
make -s -C "$here" BUILD="$build" "$build/mcg-bench-excite.ihx" > /dev/null
image=$build/mcg-bench-excite.ihx
done_addr=$(awk '$3 == "_bench_done" { print $2 }' "$build/mcg-bench-excite.map" | tail -n 1)
[ -n "$done_addr" ] || { echo "bench-excite: no _bench_done in $build/mcg-bench-excite.map" >&2; exit 1; }
cfg=$build/bench-excite.cfg
printf 'file "%s"\nbreak 0x%s\nrun\ndx 0x9f00 0x9f37 16\nquit\n' "$image" "$done_addr" > "$cfg"
out=$(timeout 300 s51 -t C517 -X 12M -C "$cfg" < /dev/null 2>&1 | sed 's/\x1b\[[0-9;]*m//g')
bytes=$(printf '%s\n' "$out" | awk '/^0x9f[0-9a-f]0 / { for (i = 2; i <= 17 && i <= NF; i++) if ($i ~ /^[0-9a-f][0-9a-f]$/) print $i }' | head -n 56)
[ "$(printf '%s\n' "$bytes" | wc -l)" -eq 56 ] || { echo "bench-excite: no figures from s51" >&2; printf '%s\n' "$out" >&2; exit 1; }
printf '%s\n' "$bytes" | while read -r h; do printf '%d\n' "0x$h"; done | awk -v want="$want_crc" -v want_chirp="$want_chirp" '
  { b[NR - 1] = $1 + 0 }
  function u16(i) { return b[i] + 256 * b[i + 1] }
  function u32(i) { return u16(i) + 65536 * u16(i + 2) }
  END {
    split("idle prbs-hold prbs-bit prbs-rpm stair chirp", name, " ")
    n[1] = 256; n[2] = 128; n[3] = 256; n[4] = 256; n[5] = 256; n[6] = 256
    printf "excite_tick on the 80C515 core at 12 MHz (s51 -t C517)\n"
    printf "timer read overhead subtracted: %d cycles\n", u16(48)
    printf "%-11s %8s %8s %8s %10s\n", "set", "min", "mean", "max", "max/tick"
    for (m = 0; m < 6; m++) {
      o = 8 * m
      printf "%-11s %8d %8.1f %8d %9.1f%%\n", name[m + 1], u16(o), u32(o + 4) / n[m + 1], u16(o + 2), u16(o + 2) / 10
    }
    worst = u16(10) > u16(18) ? u16(10) : u16(18)
    if (u16(34) > worst) worst = u16(34)
    chirp = u16(42)
    printf "prbs-hold: a bit held (exc_div 2); prbs-bit, stair, chirp: a new level every tick (exc_div 1)\n"
    printf "prbs-rpm: a new rpm_cmd every tick in mode pi (control_set_q8 included)\n"
    printf "crc16 of 10000 PRBS duties: 0x%04x, of 10000 chirp duties: 0x%04x\n", u16(50), u16(52)
    printf "a chirp'"'"'s start (exc_run 1: the sine table scaled, in the link'"'"'s write, not a tick): %d cycles\n", u16(54)
    printf "goal: prbs, stair on the duty <= 250 machine cycles (25 %% of the tick): %s\n", (worst > 250 ? "MISSED" : "met")
    printf "goal: chirp on the duty <= 600 machine cycles (60 %% of the tick): %s\n", (chirp > 600 ? "MISSED" : "met")
    rpm = u16(26)
    printf "goal: prbs-rpm <= 700 machine cycles (with the PID within the tick): %s\n",
      (rpm > 700 ? "MISSED" : "met")
    crc = sprintf("0x%04x", u16(50))
    if (want != "" && tolower(want) != crc) {
      printf "PRBS crc16 %s differs from the host core'"'"'s %s\n", crc, want
      exit 1
    }
    crc = sprintf("0x%04x", u16(52))
    if (want_chirp != "" && tolower(want_chirp) != crc) {
      printf "chirp crc16 %s differs from the host core'"'"'s %s\n", crc, want_chirp
      exit 1
    }
    exit worst > 250 || chirp > 600 || rpm > 700
  }'
