#!/usr/bin/env bash
# mcg-fit gap on varied self-made rigs (tests/sh/rigs_lib.sh): one row per rig with what gap
# named against the withheld truth, its shrink, each withheld parameter against its truth in
# standard errors, and the wall and CPU time. One run at a time, with GAP_RIGS_THREADS threads
# (default 1; 0: gap's default, every core).
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
threads=${GAP_RIGS_THREADS:-1}
for spec in "$@"; do
  kind=${spec%%:*} seed=${spec##*:} dir="$work/$kind-$seed"
  rig "$kind" "$seed" "$dir"
  mapfile -t drive <"$dir/args"
  status=0
  # Wall and CPU seconds: on a shared machine the wall time (and what the budget cuts) follows the load.
  TIMEFORMAT='%R %U %S'
  { time mcg-fit gap --threads "$threads" --budget "$budget" --config "$dir/given.ini" "${drive[@]}" \
    --train "$dir/train.csv" --validate "$dir/validate.csv" >"$dir/gap.csv" 2>"$dir/gap.err"; } \
    2>"$dir/time" || status=$?
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
  read -r wall user sys <"$dir/time"
  printf '%s:%s | want %s | got %s | shrink %s | exit %s | %.0f s, cpu %.0f s |%s\n' "$kind" "$seed" "$want" \
    "${got:-?}" "$(cut -d, -f4 <<<"$row")" "$status" "$wall" \
    "$(awk -v u="$user" -v s="$sys" 'BEGIN { print u + s }')" \
    "$params"
  [[ -z $keep ]] || { mkdir -p "$keep" && cp -r "$dir" "$keep/"; }
done
