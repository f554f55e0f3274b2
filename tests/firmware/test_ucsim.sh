#!/usr/bin/env bash
# test_ucsim.sh FIRMWARE_DIR WORKDIR UCSIM_CHECK: builds the SIM image with SDCC and runs it in s51
# under ucsim_check (version, registers, resync, the RAM log at 0x9500). Exit 125 = skipped: no
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
make -s -C "$firmware" BUILD="$work/build" "$work/build/mcg-ucsim.ihx" > "$work/make.log" 2>&1 ||
  { cat "$work/make.log" >&2; exit 1; }
exec "$check" "$work/build/mcg-ucsim.ihx" "$work"
