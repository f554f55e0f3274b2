#!/usr/bin/env bash
# test_ucsim.sh FIRMWARE_DIR WORKDIR UCSIM_CHECK: builds the SIM image with SDCC and runs it in s51
# under ucsim_check (version, registers, resync, the RAM log at 0x9500, the 8051 controller against
# the host's). Exit 125 = skipped: no
# sdcc or no s51 on this machine.
set -euo pipefail
firmware=$1
work=$2
check=$3
for tool in sdcc s51 timeout; do
  if ! command -v "$tool" > /dev/null; then
    echo "test_ucsim: $tool not found, skipped" >&2
    exit 125
  fi
done
mkdir -p "$work"
# All images: the 80C515 one must build and fit too.
make -s -C "$firmware" BUILD="$work/build" all bench > "$work/make.log" 2>&1 ||
  { cat "$work/make.log" >&2; exit 1; }
grep -E '\.ihx:|code|external' "$work/make.log" || true
exec "$check" "$work/build/mcg-ucsim.ihx" "$work" "$work/build/mcg-bench.ihx"
