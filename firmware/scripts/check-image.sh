#!/bin/sh
# check-image.sh IMAGE.ihx: prints the image's memory use (from SDCC's .mem) and fails if any
# floating-point helper got linked in (the firmware is fixed point only).
set -eu
ihx=$1
base=${ihx%.ihx}
if grep -q '___fs' "$base.map"; then
  echo "$ihx: floating-point helpers linked in (fixed point only):" >&2
  grep -o '___fs[a-z0-9_]*' "$base.map" | sort -u >&2
  exit 1
fi
echo "$(basename "$ihx"):"
grep -E '^ *(ROM/EPROM/FLASH|EXTERNAL RAM) ' "$base.mem" |
  awk '{ printf "  %-13s %6d of %6d bytes\n", ($1 == "ROM/EPROM/FLASH" ? "code" : "external RAM"), $(NF-1), $NF }'
grep -E '^Stack starts' "$base.mem" | sed 's/^/  /'
