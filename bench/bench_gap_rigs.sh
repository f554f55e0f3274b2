#!/usr/bin/env bash
# mcg-fit gap on varied self-made rigs (tests/sh/rigs_lib.sh): one row per rig with what gap
# named against the withheld truth, its shrink, each withheld parameter against its truth in
# standard errors, and the wall time. One run at a time, one thread each.
# Args: TOOL_DIR BUDGET_S KIND:SEED... (e.g. deadband:1 gearmotor:2 current:3); GAP_RIGS_KEEP=DIR keeps
# each rig's files and gap output there.
set -euo pipefail
tools=$1
budget=$2
shift 2
export PATH="$tools:$PATH"
source "$(dirname "$0")/../tests/sh/lib.sh"
source "$(dirname "$0")/../tests/sh/rigs_lib.sh"
keep=${GAP_RIGS_KEEP:-}
for spec in "$@"; do
  kind=${spec%%:*} seed=${spec##*:} dir="$work/$kind-$seed"
  rig "$kind" "$seed" "$dir"
  mapfile -t drive <"$dir/args"
  t0=$(date +%s%N)
  status=0
  mcg-fit gap --threads 1 --budget "$budget" --config "$dir/given.ini" "${drive[@]}" \
    --train "$dir/train.csv" --validate "$dir/validate.csv" >"$dir/gap.csv" 2>"$dir/gap.err" || status=$?
  t1=$(date +%s%N)
  row=$(grep -v '^#' "$dir/gap.csv" | sed -n 2p || true)
  want=$(awk '$1 == "effects" { print $2 }' "$dir/truth")
  got=$(cut -d, -f1 <<<"$row")
  params=$(awk -v row="$row" '$1 != "effects" {
      n = split(row, f, /[ ,"]/); v = ""; e = ""
      for (k = 1; k <= n; k++) if (index(f[k], $1 "=") == 1) {
        x = f[k]; sub(/^[^=]*=/, "", x); split(x, p, /[+]-/); v = p[1]; e = p[2] }
      key = $1; sub(/^[a-z_]*\./, "", key)
      if (v == "") printf " %s -(%.3g)", key, $2
      else printf " %s %.3g+-%.2g(%.3g)%s", key, v, e, $2, (e > 0 ? sprintf(" %+.1fSE", (v - $2) / e) : "")
    }' "$dir/truth")
  seconds=$(awk -v a="$t0" -v b="$t1" 'BEGIN { print (b - a) / 1e9 }')
  printf '%s:%s | want %s | got %s | shrink %s | exit %s | %.0f s |%s\n' "$kind" "$seed" "$want" "${got:-?}" \
    "$(cut -d, -f4 <<<"$row")" "$status" "$seconds" "$params"
  [[ -z $keep ]] || { mkdir -p "$keep" && cp -r "$dir" "$keep/"; }
done
