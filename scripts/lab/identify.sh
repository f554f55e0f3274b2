#!/usr/bin/env bash
# Identifies the rig from a folder of measured runs: one grey-box fit per file, spread over
# the local cores with GNU parallel or, with --sshlogin, over lab machines that have mcg
# installed; one table out (one row per file), in file-name order.
#
# Usage: identify.sh [--jobs N] [--sshlogin LOGINS] [--free P1,P2,...] [--config F.ini] DIR > fits.csv
#   --sshlogin LOGINS  GNU parallel's list, e.g. '4/lab1,4/lab2,:' (':' = this machine); the
#                      runs are transferred to the remote machines and the rows come back.
# Every file that fails to fit is reported on stderr and makes the exit status non-zero; its
# row still appears, with converged = 0 and empty values.
set -euo pipefail
jobs=0
sshlogin=""
fit_args=()
while [ $# -gt 1 ]; do
  case "$1" in
    --jobs) jobs=$2; shift 2 ;;
    --sshlogin) sshlogin=$2; shift 2 ;;
    --free|--config|--outputs) fit_args+=("$1" "$2"); shift 2 ;;
    *) echo "identify.sh: error: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[ $# = 1 ] && [ -d "$1" ] || { echo "identify.sh: error: usage: identify.sh [options] DIR" >&2; exit 2; }
dir=$1
command -v parallel >/dev/null || { echo "identify.sh: error: GNU parallel is not installed (apt-get install parallel)" >&2; exit 2; }
mapfile -t files < <(find "$dir" -maxdepth 1 -name '*.csv' | LC_ALL=C sort)
[ ${#files[@]} -gt 0 ] || { echo "identify.sh: error: $dir: no .csv files" >&2; exit 2; }
rows=$(mktemp -d)
trap 'rm -rf "$rows"' EXIT
remote=()
[ -n "$sshlogin" ] && remote=(--sshlogin "$sshlogin" --transferfile {} --cleanup)
[ "$jobs" = 0 ] && jobs=100%
# Each job is one single-threaded fit writing a one-row table DIR/K.csv and its status DIR/K.rc,
# the layout of the Slurm array, so the same merge-rows.sh joins them in file order.
printf '%s\n' "${files[@]}" > "$rows/list"
printf '%s\n' "${files[@]}" | parallel --will-cite --jobs "$jobs" "${remote[@]}" --halt never \
  "mcg-fit model --batch --threads 1 ${fit_args[*]} {} > $rows/{#}.csv 2> $rows/{#}.err; echo \$? > $rows/{#}.rc" || true
for k in $(seq 1 ${#files[@]}); do
  [ -s "$rows/$k.err" ] && sed "s|^|identify.sh: ${files[$((k - 1))]}: |" "$rows/$k.err" >&2
done
MERGE_SOURCE="scripts/lab/identify.sh (GNU parallel, mcg-fit model --batch per file)" \
  "$(dirname "$0")/merge-rows.sh" "$rows/list" "$rows"
