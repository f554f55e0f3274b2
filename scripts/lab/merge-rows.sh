#!/usr/bin/env bash
# Merges the one-row tables of an identification array (identify.sbatch, identify.sh) into one table,
# rows in list order; reports files whose fit failed and exits non-zero if any did.
# Usage: merge-rows.sh LIST DIR > fits.csv
set -euo pipefail
list=$1
dir=$2
mapfile -t files < "$list"
status=0
first=1
for k in $(seq 1 ${#files[@]}); do
  rc=$(cat "$dir/$k.rc" 2>/dev/null || echo missing)
  [ "$rc" = 0 ] || { echo "merge-rows.sh: ${files[$((k - 1))]}: fit status $rc" >&2; status=1; }
  [ -s "$dir/$k.csv" ] || continue
  if [ $first = 1 ]; then
    echo "# source: ${MERGE_SOURCE:-scripts/lab/merge-rows.sh (Slurm array of mcg-fit model --batch)}"
    for j in $(seq 1 ${#files[@]}); do echo "# file.$j: ${files[$((j - 1))]}"; done
    grep -v '^#' "$dir/$k.csv" | head -1
    first=0
  fi
  grep -v '^#' "$dir/$k.csv" | tail -n +2 | sed "s/^1,/$k,/"
done
exit $status
